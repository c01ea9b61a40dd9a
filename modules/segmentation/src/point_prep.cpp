// Point preparation: checks the scan, XYZ of every return in range (gyro de-skewed to mid-sweep when
// GyroDeskew can), and in the same pass the candidate sets of the plane fits (upper / lower half rings).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "fploc/segmentation/segmenter.h"

namespace fploc::seg {

namespace {
bool same_beams(const BeamIntrinsics& a, const BeamIntrinsics& b) {
  return a.altitude_deg == b.altitude_deg && a.azimuth_deg == b.azimuth_deg &&
         a.beam_offset_mm == b.beam_offset_mm && a.lidar_to_sensor == b.lidar_to_sensor;
}
}  // namespace

bool Segmenter::prepare(const Scan& scan) {
  out_.height = scan.height;
  out_.width = scan.width;
  auto fail = [&](SegStatus st, std::string why) {
    out_.status = st;
    out_.status_text = std::move(why);
    return false;
  };
  if (scan.height <= 0 || scan.width <= 0) return fail(SegStatus::kEmpty, "empty scan (no rows/columns)");
  const size_t n = size_t(scan.height) * scan.width;
  if (scan.range_mm.size() != n)
    return fail(SegStatus::kBadInput, "range_mm has " + std::to_string(scan.range_mm.size()) + " pixels, expected " +
                                          std::to_string(scan.height) + "x" + std::to_string(scan.width));
  if (scan.beams.beams() != scan.height || int(scan.beams.azimuth_deg.size()) != scan.height)
    return fail(SegStatus::kBadInput, "beam intrinsics have " + std::to_string(scan.beams.beams()) +
                                          " beams but the scan has " + std::to_string(scan.height) + " rows");
  if (scan.height < 4) return fail(SegStatus::kBadInput, "too few beams (" + std::to_string(scan.height) + ")");
  for (double a : scan.beams.altitude_deg)
    if (!std::isfinite(a) || std::abs(a) > 90) return fail(SegStatus::kBadInput, "beam altitude not finite or > 90 deg");
  for (double a : scan.beams.azimuth_deg)
    if (!std::isfinite(a)) return fail(SegStatus::kBadInput, "beam azimuth not finite");

  if (lut_width_ != scan.width || !same_beams(lut_beams_, scan.beams)) {
    lut_ = make_xyz_lut(scan.beams, scan.width);
    lut_beams_ = scan.beams;
    lut_width_ = scan.width;
    ring_order_.resize(scan.height);
    std::iota(ring_order_.begin(), ring_order_.end(), 0);
    std::stable_sort(ring_order_.begin(), ring_order_.end(),
                     [&](int a, int b) { return scan.beams.altitude_deg[a] > scan.beams.altitude_deg[b]; });
    scale_ = seg::beam_scaling(scan.beams, scan.width, cfg_);
  }
  xyz_.resize(n);
  range_.resize(n);
  // Rotation de-skew: a return measured at column time t_c is rotated into the sensor frame at mid-sweep,
  // p_mid = R_mid<-c p, R integrated from the gyro (body frame = sensor frame; see GyroDeskew).
  // Only rotation matters for the planes: yaw rate leaves heights unchanged, roll/pitch rates tilt them (a few tenths of a degree per sweep when the platform wobbles, worst in corridors where the
  // ceiling is seen in two short azimuth windows). Translation during the sweep shifts heights by
  // v_z * 0.05 s (mm). Wall points are published as measured (with their times): downstream compensates.
  const bool deskew = deskew_.prepare(scan);
  out_.deskewed = deskew;
  if (deskew) raw_.resize(n);
  const std::vector<Eigen::Matrix3f>& rots = deskew_.rotations();
  // Range gate in integers: float(r) < rmin || float(r) > rmax for the 20-bit ranges (exact in float).
  const float rmin = float(cfg_.min_range_m * 1000.0), rmax = float(cfg_.max_range_m * 1000.0);
  const uint32_t r_lo = uint32_t(std::clamp(std::ceil(double(rmin)), 1.0, 4294967295.0));
  const uint32_t r_hi = uint32_t(std::clamp(std::floor(double(rmax)), 0.0, 4294967295.0));
  // Per column (once, not per pixel): look-up column (measurement id) and validity.
  const int W = scan.width, H = scan.height;
  const bool mids = int(scan.measurement_id.size()) == W;
  const bool cvalid = int(scan.column_valid.size()) == W;
  col_mid_.resize(W);
  col_ok_.resize(W);
  for (int c = 0; c < W; ++c) {
    int mid = mids ? scan.measurement_id[c] : c;
    if (mid < 0 || mid >= W) mid = c;
    col_mid_[c] = mid;
    col_ok_[c] = !(cvalid && !scan.column_valid[c]);
  }
  // XYZ of every valid pixel, and in the same pass the candidate sets: upper half rings (top first) and
  // lower half rings (bottom first), each ring in column order (an odd middle ring is in neither).
  // The candidate arrays are sized for every pixel of their rings up front and cut to the valid count after
  // (no push_back per point); an invalid pixel is written too and overwritten by the next valid one.
  size_t valid = 0;
  const float* dir = lut_.direction.data();
  const float* off = lut_.offset.data();
  const uint32_t* rng = scan.range_mm.data();
  auto ring_pass = [&](int u, Candidates* cs, size_t& m) {
    const size_t row = size_t(u) * W;
    Eigen::Vector3f* cp = cs ? cs->p.data() : nullptr;
    float* cxs = cs ? cs->x.data() : nullptr;
    float* cys = cs ? cs->y.data() : nullptr;
    float* czs = cs ? cs->z.data() : nullptr;
    float* cr = cs ? cs->range.data() : nullptr;
    int32_t* cx = cs ? cs->pixel.data() : nullptr;
    for (int c = 0; c < W; ++c) {
      const size_t i = row + c;
      const uint32_t r = rng[i];
      if (r < r_lo || r > r_hi || !col_ok_[c]) {
        range_[i] = 0.f;
        continue;
      }
      const size_t k = 3 * (row + col_mid_[c]);
      const float fr = float(r);
      Eigen::Vector3f p(dir[k] * fr + off[k], dir[k + 1] * fr + off[k + 1], dir[k + 2] * fr + off[k + 2]);
      if (deskew) {
        raw_[i] = p;
        p = rots[c] * p;
      }
      xyz_[i] = p;
      const float rm = fr * 1e-3f;
      range_[i] = rm;
      ++valid;
      if (cs) {
        cp[m] = p;
        cxs[m] = p.x();
        cys[m] = p.y();
        czs[m] = p.z();
        cr[m] = rm;
        cx[m] = int32_t(i);
        ++m;
      }
    }
    if (cs) cs->ring_start.push_back(int32_t(m));
  };
  const int half = H / 2;
  for (Candidates* cs : {&upper_, &lower_}) {
    // Not cleared first: resize only initialises what the last scan's valid count left short of the full size.
    cs->ring_start.assign(1, 0);
    cs->width = W;
    cs->seed_rings = scale_.seed_rings;
    cs->start_stride = scale_.start_stride;
    cs->final_stride = scale_.final_stride;
    cs->p.resize(size_t(half) * W);
    cs->x.resize(size_t(half) * W + Candidates::kLanes);
    cs->y.resize(size_t(half) * W + Candidates::kLanes);
    cs->z.resize(size_t(half) * W + Candidates::kLanes);
    cs->range.resize(size_t(half) * W);
    cs->pixel.resize(size_t(half) * W);
  }
  size_t mu = 0, ml = 0, mm = 0;
  for (int k = 0; k < half; ++k) ring_pass(ring_order_[k], &upper_, mu);
  for (int k = 0; k < half; ++k) ring_pass(ring_order_[H - 1 - k], &lower_, ml);
  if (H % 2 == 1) ring_pass(ring_order_[half], nullptr, mm);
  for (auto [cs, m] : {std::pair{&upper_, mu}, std::pair{&lower_, ml}}) {
    cs->p.resize(m);
    const size_t padded = (m + Candidates::kLanes - 1) / Candidates::kLanes * Candidates::kLanes;
    for (auto* v : {&cs->x, &cs->y, &cs->z}) {
      v->resize(padded);
      std::fill(v->begin() + m, v->end(), std::numeric_limits<float>::quiet_NaN());
    }
    cs->range.resize(m);
    cs->pixel.resize(m);
  }
  if (valid == 0) return fail(SegStatus::kEmpty, "no valid returns in the scan");
  return true;
}

}  // namespace fploc::seg
