// Wall selection: the returns between the floor and the ceiling (with margins), as measured, ring-major in
// destaggered column order, with their column times (motion compensation downstream).
#include <algorithm>

#include "fploc/segmentation/segmenter.h"
#include "segmenter_constants.h"

namespace fploc::seg {

void Segmenter::select_walls(const Scan& scan, const Eigen::Vector3d& up) {
  // Upper bound: the ceiling (this frame's or last known), else (no ceiling ever accepted: the start under an
  // atrium, or next to a higher hall whose returns fail the ceiling's "rays end there" test) a plane
  // parallel to the ground kNoCeilingWallTopM above the floor; lower bound: the ground plane, else a plane
  // parallel to the ceiling one room height below, else last known ground.
  Eigen::Vector4d ceil, floor;
  double mc = cfg_.wall_margin_m, mf = cfg_.wall_margin_m;
  if (out_.ceiling.found) {
    ceil = out_.ceiling.coeffs;
    mc = std::max(mc, k::kPlaneMarginRms * out_.ceiling.rms_m);
  } else if (have_prev_ceiling_) {
    ceil = prev_ceiling_;
    mc *= k::kHeldPlaneMarginGrowth;
  } else if (out_.ground.found) {
    ceil << -out_.ground.coeffs.head<3>(), std::max(k::kNoCeilingWallTopM - out_.ground.distance(), k::kMinCeilingDistM);
    if (!out_.status_text.empty()) out_.status_text += "; ";
    out_.status_text += "no ceiling known: wall points up to 2 m above the floor";
  } else {
    if (!out_.status_text.empty()) out_.status_text += "; ";
    out_.status_text += "no ceiling known: no wall points";
    return;
  }
  const double H = height_.known_room_height();
  if (out_.ground.found) {
    floor = out_.ground.coeffs;
    mf = std::max(mf, k::kPlaneMarginRms * out_.ground.rms_m);
  } else if (H > 0) {
    floor << -ceil.head<3>(), H - ceil[3];
  } else if (have_prev_ground_) {
    floor = prev_ground_;
    mf *= k::kHeldPlaneMarginGrowth;
  } else {
    floor << up, ceil[3];  // last resort: assume the sensor at mid height
  }
  const Eigen::Vector3f nc = ceil.head<3>().cast<float>(), nf = floor.head<3>().cast<float>();
  const float dc = float(ceil[3] - mc), df = float(floor[3] - mf);
  const float cin = float(ceil[3] - cfg_.inlier_threshold_m), fin = float(floor[3] - cfg_.inlier_threshold_m);
  const int W = scan.width;
  auto& w = out_.wall;
  const size_t cap = size_t(scan.height) * W;
  w.x.reserve(cap); w.y.reserve(cap); w.z.reserve(cap); w.range.reserve(cap); w.t.reserve(cap); w.ring.reserve(cap); w.column.reserve(cap);
  const bool labels = keep_labels_, deskewed = out_.deskewed;
  const float* rng = range_.data();
  const Eigen::Vector3f* xyz = xyz_.data();
  // Column time offsets (staggered column = measurement order), for motion compensation downstream.
  col_dt_.assign(W, 0.f);
  if (scan.column_utime.size() == size_t(W))
    for (int v = 0; v < W; ++v)
      if (scan.column_utime[v] != 0) col_dt_[v] = float(double(scan.column_utime[v] - scan.utime) * 1e-6);
  for (int u = 0; u < scan.height; ++u) {
    const int shift = u < int(scan.beams.pixel_shift_by_row.size()) ? scan.beams.pixel_shift_by_row[u] : 0;
    int v = ((-shift) % W + W) % W;  // staggered column of destaggered column cd (cd - shift mod W)
    for (int cd = 0; cd < W; ++cd, ++v) {
      if (v == W) v = 0;
      const size_t i = size_t(u) * W + v;
      const float r = rng[i];
      if (r <= 0.f) continue;
      const Eigen::Vector3f& p = xyz[i];
      const float sc = nc.dot(p), sf = nf.dot(p);
      if (sc > -dc && sf > -df) {
        w.push(deskewed ? raw_[i] : p, r, u, cd, col_dt_[v]);  // as measured (see prepare())
        if (labels) out_.label[i] = 3;
      } else if (labels) {
        if (sc <= -cin) out_.label[i] = 1;
        else if (sf <= -fin) out_.label[i] = 2;
      }
    }
  }
}

}  // namespace fploc::seg
