// Wall selection: the returns between the floor and the ceiling (with margins), as measured, ring-major in
// destaggered column order, with their column times (motion compensation downstream).
#include <algorithm>
#include <cstring>

#include "fploc/segmentation/segmenter.h"
#include "plane_kernels.h"
#include "segmenter_constants.h"
#include "simd4.h"
#include "wall_kernels.h"

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
    out_.note("no ceiling known: wall points up to 2 m above the floor");
  } else {
    out_.note("no ceiling known: no wall points");
    out_.wall.clear();
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
  const int W = scan.width, rows = scan.height;
  // Column time offsets (staggered column = measurement order), for motion compensation downstream.
  col_dt_.assign(W, 0.f);
  if (scan.column_utime.size() == size_t(W))
    for (int v = 0; v < W; ++v)
      if (scan.column_utime[v] != 0) col_dt_[v] = float(double(scan.column_utime[v] - scan.utime) * 1e-6);

  // The returns of each scan row are one ring of the candidates, in staggered column order; in destaggered
  // order (cd = v + shift mod W) the ring starts at the first staggered column >= v0 = -shift mod W and
  // wraps around: two contiguous pieces per row. A wall point lies below the ceiling and above the floor
  // (with margins); the test runs four candidates at a time.
  using namespace simd;
  const v4f ncx = splat(nc.x()), ncy = splat(nc.y()), ncz = splat(nc.z()), mdc = splat(-dc);
  const v4f nfx = splat(nf.x()), nfy = splat(nf.y()), nfz = splat(nf.z()), mdf = splat(-df);
  const Candidates* sets[3] = {&upper_, &lower_, &middle_};
  // Piece: candidates [a, b) of row u; destaggered column = pixel index + off.
  using Piece = WallPiece;
  pieces_.clear();
  for (int u = 0; u < rows; ++u) {
    const Candidates& cs = *sets[row_set_[u]];
    const int k = row_ring_[u];
    const int32_t rs = cs.ring_start[k], re = cs.ring_start[k + 1];
    const int shift = u < int(scan.beams.pixel_shift_by_row.size()) ? scan.beams.pixel_shift_by_row[u] : 0;
    const int v0 = ((-shift) % W + W) % W;
    const int32_t row = u * W;
    const int32_t sp = int32_t(std::lower_bound(cs.pixel.begin() + rs, cs.pixel.begin() + re, row + v0) - cs.pixel.begin());
    pieces_.push_back({&cs, sp, re, -row - v0, int16_t(u)});
    pieces_.push_back({&cs, rs, sp, -row - v0 + W, int16_t(u)});
  }
  auto& w = out_.wall;
  const bool deskewed = out_.deskewed;
  // Eight candidates at a time (AVX2 CPUs): the same tests and copies (wall_kernels.h); de-skewed scans only
  // when the look-up column is the scan's own (the per-pixel table lut_soa_).
  if (wallk::available() && kern::wide() && (!deskewed || col_identity_)) {
    const wallk::Bounds bd{nc.x(), nc.y(), nc.z(), -dc, nf.x(), nf.y(), nf.z(), -df};
    size_t groups = 0;
    for (const Piece& pc : pieces_) groups += size_t((pc.b - pc.a + 7) / 8);
    masks_.resize(groups);
    size_t m = 0, g = 0;
    for (const Piece& pc : pieces_) {
      m += wallk::masks8(pc.cs->x.data(), pc.cs->y.data(), pc.cs->z.data(), pc.a, pc.b, bd, masks_.data() + g);
      g += size_t((pc.b - pc.a + 7) / 8);
    }
    for (auto* v : {&w.x, &w.y, &w.z, &w.range, &w.t}) v->resize(m + 8);  // 8 slots of slack for the block stores
    w.ring.resize(m + 8);
    w.column.resize(m + 8);
    const wallk::Out out{w.x.data(), w.y.data(), w.z.data(), w.range.data(), w.t.data(), w.ring.data(), w.column.data()};
    // De-skewed: the returns as measured, stored beside the candidates by the preparation (has_raw), else
    // computed again from the range and the table.
    const bool raw = deskewed && upper_.has_raw && lower_.has_raw && (middle_.n == 0 || middle_.has_raw);
    wallk::Measured meas{};
    if (deskewed && !raw) {
      for (int e = 0; e < 6; ++e) meas.lut[e] = lut_soa_[e].data();
      meas.range_mm = scan.range_mm.data();
    }
    size_t o = 0;
    g = 0;
    for (const Piece& pc : pieces_) {
      const Candidates& cs = *pc.cs;
      // (a row whose measured z the preparation did not store: taken from the range, Source::zrow)
      const float* zr = raw && raw_z_from_range_ && !std::isnan(row_z_[size_t(pc.u)][0]) ? row_z_[size_t(pc.u)].data() : nullptr;
      const wallk::Source src = raw ? wallk::Source{cs.raw_x.data(), cs.raw_y.data(), cs.raw_z.data(), cs.range.data(), cs.pixel.data(), zr}
                                    : wallk::Source{cs.x.data(), cs.y.data(), cs.z.data(), cs.range.data(), cs.pixel.data()};
      o = wallk::copy8(src, pc.a, pc.b, int32_t(pc.u) * W, pc.off, pc.u, masks_.data() + g, col_dt_.data(),
                       deskewed && !raw ? &meas : nullptr, out, o);
      g += size_t((pc.b - pc.a + 7) / 8);
    }
    for (auto* v : {&w.x, &w.y, &w.z, &w.range, &w.t}) v->resize(m);
    w.ring.resize(m);
    w.column.resize(m);
  } else {
  auto mask = [&](const Candidates& cs, int32_t j, int32_t b) {
    const v4f x = load(cs.x.data() + j), y = load(cs.y.data() + j), z = load(cs.z.data() + j);
    const v4i in = (ncx * x + ncy * y + ncz * z > mdc) & (nfx * x + nfy * y + nfz * z > mdf);
    return movemask(in) & ((1 << std::min(4, b - j)) - 1);  // lanes past the piece's end: off
  };
  static constexpr uint8_t kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};  // set bits
  // Count first (the output arrays are sized once, not grown point by point); the masks are kept for the
  // second pass.
  size_t m = 0, groups = 0;
  for (const Piece& pc : pieces_) groups += size_t((pc.b - pc.a + 3) / 4);
  masks_.resize(groups);
  {
    size_t g = 0;
    for (const Piece& pc : pieces_)
      for (int32_t j = pc.a; j < pc.b; j += 4) {
        const int mk = mask(*pc.cs, j, pc.b);
        masks_[g++] = uint8_t(mk);
        m += size_t(kBits[mk]);
      }
  }
  for (auto* v : {&w.x, &w.y, &w.z, &w.range, &w.t}) v->resize(m);
  w.ring.resize(m);
  w.column.resize(m);
  float *ox = w.x.data(), *oy = w.y.data(), *oz = w.z.data(), *orng = w.range.data(), *ot = w.t.data();
  int16_t *oring = w.ring.data(), *ocol = w.column.data();
  const float* dir = lut_.direction.data();
  const float* lut_off = lut_.offset.data();
  size_t o = 0, g = 0;
  for (const Piece& pc : pieces_) {
    const Candidates& cs = *pc.cs;
    const int32_t row = int32_t(pc.u) * W;
    for (int32_t j = pc.a; j < pc.b; j += 4) {
      const int mk = masks_[g++];
      if (mk == 0) continue;
      if (mk == 15 && !deskewed) {
        std::memcpy(ox + o, cs.x.data() + j, 4 * sizeof(float));
        std::memcpy(oy + o, cs.y.data() + j, 4 * sizeof(float));
        std::memcpy(oz + o, cs.z.data() + j, 4 * sizeof(float));
        std::memcpy(orng + o, cs.range.data() + j, 4 * sizeof(float));
        const int32_t pix0 = cs.pixel[j];
        if (cs.pixel[j + 3] == pix0 + 3) {  // four neighbouring columns (no dropout between): copied as a block
          std::memcpy(ot + o, col_dt_.data() + (pix0 - row), 4 * sizeof(float));
          const int16_t c0 = int16_t(pix0 + pc.off);
          const int16_t cols[4] = {c0, int16_t(c0 + 1), int16_t(c0 + 2), int16_t(c0 + 3)};
          std::memcpy(ocol + o, cols, sizeof cols);
        } else {
          for (int l = 0; l < 4; ++l) {
            const int32_t pix = cs.pixel[j + l];
            ot[o + l] = col_dt_[pix - row];
            ocol[o + l] = int16_t(pix + pc.off);
          }
        }
        const int16_t rings[4] = {pc.u, pc.u, pc.u, pc.u};
        std::memcpy(oring + o, rings, sizeof rings);
        o += 4;
        continue;
      }
      for (int l = 0; l < 4; ++l) {
        if (!((mk >> l) & 1)) continue;
        const size_t q = size_t(j + l);
        const int32_t pix = cs.pixel[q];
        if (deskewed) {  // as measured (see prepare()): the return before the de-skew rotation
          const int c = pix - row;
          const size_t kk = 3 * (size_t(row) + col_mid_[c]);
          const float fr = float(scan.range_mm[size_t(pix)]);
          ox[o] = dir[kk] * fr + lut_off[kk];
          oy[o] = dir[kk + 1] * fr + lut_off[kk + 1];
          oz[o] = dir[kk + 2] * fr + lut_off[kk + 2];
        } else {
          ox[o] = cs.x[q];
          oy[o] = cs.y[q];
          oz[o] = cs.z[q];
        }
        orng[o] = cs.range[q];
        ot[o] = col_dt_[pix - row];
        oring[o] = pc.u;
        ocol[o] = int16_t(pix + pc.off);
        ++o;
      }
    }
  }
  }
  if (keep_labels_) {  // bench/tests: 1 ceiling inlier, 2 ground inlier, 3 wall point
    const float cin = float(ceil[3] - cfg_.inlier_threshold_m), fin = float(floor[3] - cfg_.inlier_threshold_m);
    for (const Candidates* cs : sets)
      for (size_t j = 0; j < cs->n; ++j) {
        const Eigen::Vector3f p = cs->point(j);
        const float sc = nc.dot(p), sf = nf.dot(p);
        uint8_t& lab = out_.label[size_t(cs->pixel[j])];
        if (sc > -dc && sf > -df) lab = 3;
        else if (sc <= -cin) lab = 1;
        else if (sf <= -fin) lab = 2;
      }
  }
}

}  // namespace fploc::seg
