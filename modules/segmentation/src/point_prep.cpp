// Point preparation: checks the scan, XYZ of every return in range (gyro de-skewed to mid-sweep when
// GyroDeskew can), and in the same pass the candidate sets of the plane fits (upper / lower half rings).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>

#include "fploc/segmentation/segmenter.h"
#include "compact_kernels.h"
#include "plane_kernels.h"
#include "wall_kernels.h"
#include "simd4.h"
#if defined(__x86_64__) && defined(__GNUC__)
#include "lane8.h"
#endif

// (the eight-lane vectors stay inside the AVX2 functions: GCC's ABI note for them does not apply)
#pragma GCC diagnostic ignored "-Wpsabi"

namespace fploc::seg {

namespace {
#if defined(__x86_64__) && defined(__GNUC__)
#define FPLOC_PREP_WIDE 1
constexpr lane8::CompressTable<false> kCompress;
// One scan row of the four-column pass below, eight columns at a time (AVX2, chosen at run time with the plane
// fit's kernels: kern::wide()): the same arithmetic per point (no fused multiply-add), so the same
// candidates. rng/okm/lut point at the row's first column, rot at column 0 (GyroDeskew::interleaved()); returns the new candidate count.
// zrow: the row's z direction and offset are one value each (zr[0], zr[1]; the OS-1's, whose sensor z axis is
// the lidar's: the same floats as the table's); okm null: every column valid.
template <bool kZRow, bool kAllOk>
__attribute__((target("avx2"))) size_t ring_pass8_t(const uint32_t* rng, const int32_t* okm, const float* const lut[6],
                                                    const float* zr, const float* rot, float* const raw[3],
                                                    const uint32_t* next_rng, int W, int32_t lo, int32_t hi,
                                                    int32_t pix_row, float* cx, float* cy, float* cz, float* cr,
                                                    int32_t* cp, size_t m) {
  typedef float v8f __attribute__((vector_size(32)));
  typedef int32_t v8i __attribute__((vector_size(32)));
#define FPLOC_LD(p) ({ v8f v_; std::memcpy(&v_, (p), sizeof v_); v_; })
  // The table's rows in registers (restrict: the candidate stores cannot change them).
  const float* __restrict l0 = lut[0];
  const float* __restrict l1 = lut[1];
  const float* __restrict l2 = lut[2];
  const float* __restrict l3 = lut[3];
  const float* __restrict l4 = lut[4];
  const float* __restrict l5 = lut[5];
  // (and the rotations, the measured copies and the candidates: every pointer the loop uses stays in a register)
  const float* __restrict rt = rot;
  float* __restrict rx = raw ? raw[0] : nullptr;
  float* __restrict ry = raw ? raw[1] : nullptr;
  float* __restrict rz = raw ? raw[2] : nullptr;  // (null: a row whose z wall selection takes from the range)
  float* __restrict ox = cx;
  float* __restrict oy = cy;
  float* __restrict oz = cz;
  float* __restrict orr = cr;
  int32_t* __restrict op = cp;
  const v8i lov = {lo, lo, lo, lo, lo, lo, lo, lo}, hiv = {hi, hi, hi, hi, hi, hi, hi, hi};
  const v8f mm = {1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f};
  for (int c = 0; c < W; c += 8) {
    // The next row's ranges (a row is a page: the hardware's prefetch stops at its end).
    if (next_rng) __builtin_prefetch(next_rng + c);
    v8i ri;
    std::memcpy(&ri, rng + c, sizeof ri);
    v8i inm = (ri >= lov) & (ri <= hiv);
    if constexpr (!kAllOk) {
      v8i ok;
      std::memcpy(&ok, okm + c, sizeof ok);
      inm &= ok;
    }
    const int in = __builtin_ia32_movmskps256(reinterpret_cast<v8f>(inm));
    if (in == 0) continue;
    const v8f fr = __builtin_convertvector(ri, v8f);
    v8f x = FPLOC_LD(l0 + c) * fr + FPLOC_LD(l3 + c), y = FPLOC_LD(l1 + c) * fr + FPLOC_LD(l4 + c),
        z = kZRow ? v8f{zr[0], zr[0], zr[0], zr[0], zr[0], zr[0], zr[0], zr[0]} * fr +
                        v8f{zr[1], zr[1], zr[1], zr[1], zr[1], zr[1], zr[1], zr[1]}
                  : FPLOC_LD(l2 + c) * fr + FPLOC_LD(l5 + c);
    // (de-skewed: the return as measured, before the rotation, for the wall points; stored with the candidate)
    v8f mx = x, my = y, mz = z;
    if (rt) {
      const float* g = rt + size_t(c) * 9;  // this group's 72 entries (c is a multiple of 8)
      const v8f X = FPLOC_LD(g) * x + FPLOC_LD(g + 8) * y + FPLOC_LD(g + 16) * z;
      const v8f Y = FPLOC_LD(g + 24) * x + FPLOC_LD(g + 32) * y + FPLOC_LD(g + 40) * z;
      const v8f Z = FPLOC_LD(g + 48) * x + FPLOC_LD(g + 56) * y + FPLOC_LD(g + 64) * z;
      x = X;
      y = Y;
      z = Z;
    }
    const v8f rm = fr * mm;
    const int32_t p0 = pix_row + c;
    const v8i pv = v8i{p0, p0, p0, p0, p0, p0, p0, p0} + v8i{0, 1, 2, 3, 4, 5, 6, 7};
    if (in == 255) {
      std::memcpy(ox + m, &x, sizeof x);
      std::memcpy(oy + m, &y, sizeof y);
      std::memcpy(oz + m, &z, sizeof z);
      std::memcpy(orr + m, &rm, sizeof rm);
      std::memcpy(op + m, &pv, sizeof pv);
      if (rx) {
        std::memcpy(rx + m, &mx, sizeof mx);
        std::memcpy(ry + m, &my, sizeof my);
        if (rz) std::memcpy(rz + m, &mz, sizeof mz);
      }
      m += 8;
      continue;
    }
    // Some lanes out: the kept ones moved to the front by one permutation each, eight slots stored (the slots
    // past the kept ones are free: the next group or ring writes there, the padding after the last ring).
    const __m256i idx = lane8::to_front(kCompress, in);
#define FPLOC_PERM(v) reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(v), idx))
    const v8f qx = FPLOC_PERM(x), qy = FPLOC_PERM(y), qz = FPLOC_PERM(z), qr = FPLOC_PERM(rm);
    if (rx) {
      mx = FPLOC_PERM(mx);
      my = FPLOC_PERM(my);
      std::memcpy(rx + m, &mx, sizeof mx);
      std::memcpy(ry + m, &my, sizeof my);
      if (rz) {
        mz = FPLOC_PERM(mz);
        std::memcpy(rz + m, &mz, sizeof mz);
      }
    }
#undef FPLOC_PERM
    const v8i qp = reinterpret_cast<v8i>(_mm256_permutevar8x32_epi32(reinterpret_cast<__m256i>(pv), idx));
    std::memcpy(ox + m, &qx, sizeof qx);
    std::memcpy(oy + m, &qy, sizeof qy);
    std::memcpy(oz + m, &qz, sizeof qz);
    std::memcpy(orr + m, &qr, sizeof qr);
    std::memcpy(op + m, &qp, sizeof qp);
    m += size_t(__builtin_popcount(unsigned(in)));
  }
#undef FPLOC_LD
  return m;
}
size_t ring_pass8(const uint32_t* rng, const int32_t* okm, const float* const lut[6], const float* zr,
                  const float* rot, float* const raw[3], const uint32_t* next_rng, int W, int32_t lo,
                  int32_t hi, int32_t pix_row, float* cx, float* cy, float* cz, float* cr, int32_t* cp, size_t m) {
  if (zr)
    return okm ? ring_pass8_t<true, false>(rng, okm, lut, zr, rot, raw, next_rng, W, lo, hi, pix_row, cx, cy, cz, cr, cp, m)
               : ring_pass8_t<true, true>(rng, okm, lut, zr, rot, raw, next_rng, W, lo, hi, pix_row, cx, cy, cz, cr, cp, m);
  return okm ? ring_pass8_t<false, false>(rng, okm, lut, zr, rot, raw, next_rng, W, lo, hi, pix_row, cx, cy, cz, cr, cp, m)
             : ring_pass8_t<false, true>(rng, okm, lut, zr, rot, raw, next_rng, W, lo, hi, pix_row, cx, cy, cz, cr, cp, m);
}
#else
#define FPLOC_PREP_WIDE 0
#endif

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
    {  // the table as float arrays: direction x/y/z, offset x/y/z per pixel (one pass over both matrices)
      const size_t np = size_t(lut_.direction.rows());
      for (auto& a : lut_soa_) a.resize(np);
      const float* d = lut_.direction.data();  // (row-major: pixel i's x, y, z at 3 i)
      const float* o = lut_.offset.data();
      float *dx = lut_soa_[0].data(), *dy = lut_soa_[1].data(), *dz = lut_soa_[2].data();
      float *ox = lut_soa_[3].data(), *oy = lut_soa_[4].data(), *oz = lut_soa_[5].data();
      for (size_t i = 0; i < np; ++i) {
        dx[i] = d[3 * i];
        dy[i] = d[3 * i + 1];
        dz[i] = d[3 * i + 2];
        ox[i] = o[3 * i];
        oy[i] = o[3 * i + 1];
        oz[i] = o[3 * i + 2];
      }
    }
    // Rows whose z direction and offset are one value each (the same floats in every column): their pair.
    row_z_.assign(size_t(scan.height), {std::numeric_limits<float>::quiet_NaN(), 0.f});
    for (int u = 0; u < scan.height; ++u) {
      const float* dz = lut_soa_[2].data() + size_t(u) * scan.width;
      const float* oz = lut_soa_[5].data() + size_t(u) * scan.width;
      bool same = true;
      for (int c = 1; c < scan.width && same; ++c) same = std::memcmp(dz + c, dz, 4) == 0 && std::memcmp(oz + c, oz, 4) == 0;
      if (same) row_z_[size_t(u)] = {dz[0], oz[0]};
    }
    // Where each scan row's returns are among the candidates (see below): its set and ring there.
    const int Hh = scan.height, hh = Hh / 2;
    row_set_.assign(Hh, 2);
    row_ring_.assign(Hh, 0);
    for (int k = 0; k < hh; ++k) {
      row_set_[ring_order_[k]] = 0;
      row_ring_[ring_order_[k]] = k;
      row_set_[ring_order_[Hh - 1 - k]] = 1;
      row_ring_[ring_order_[Hh - 1 - k]] = k;
    }
  }
  // Rotation de-skew: a return measured at column time t_c is rotated into the sensor frame at mid-sweep,
  // p_mid = R_mid<-c p, R integrated from the gyro (body frame = sensor frame; see GyroDeskew).
  // Only rotation matters for the planes: yaw rate leaves heights unchanged, roll/pitch rates tilt them (a few tenths of a degree per sweep when the platform wobbles, worst in corridors where the
  // ceiling is seen in two short azimuth windows). Translation during the sweep shifts heights by
  // v_z * 0.05 s (mm). Wall points are published as measured (with their times): downstream compensates.
  const bool deskew = deskew_.prepare(scan);
  out_.deskewed = deskew;
  // (the column rotations as floats interleaved by groups of eight columns: GyroDeskew::interleaved())
  const float* const rot_il = deskew ? deskew_.interleaved() : nullptr;
  // Range gate in integers: float(r) < rmin || float(r) > rmax for the 20-bit ranges (exact in float).
  const float rmin = float(cfg_.min_range_m * 1000.0), rmax = float(cfg_.max_range_m * 1000.0);
  const uint32_t r_lo = uint32_t(std::clamp(std::ceil(double(rmin)), 1.0, 4294967295.0));
  const uint32_t r_hi = uint32_t(std::clamp(std::floor(double(rmax)), 0.0, 4294967295.0));
  // Every candidate's range [m] gives its range in mm back exactly (wallk::Source::zrow): on a row whose z is one
  // value, a de-skewed return's measured z is computed again from it by wall selection, not stored here.
  raw_z_from_range_ = r_hi < wallk::kExactRangeMm;
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
  // One pass over the pixels writes only the candidate sets: upper half rings (top first), lower half rings
  // (bottom first), an odd middle ring on its own (no fit; wall points only); each ring in column order.
  // No per-pixel image: wall selection reads the candidates. The arrays keep their full size from scan to
  // scan (nothing re-initialised); every pixel is written at the next free slot and the slot is kept only
  // for a return in range (no branch on it: dropouts and sky are irregular).
  const float* dir = lut_.direction.data();
  const float* off = lut_.offset.data();
  const uint32_t* rng = scan.range_mm.data();
  // Four columns at a time when the look-up columns are the scan's own (measurement id = column, the usual
  // case) and the width is a multiple of 4: the table as float arrays (lut_soa_, built with the table), the
  // range gate and column validity as a lane mask, and four slots written at once when all four are kept
  // (most of a ring). The arithmetic is the same per point as the scalar pass.
  bool identity = W % 4 == 0;
  for (int c = 0; c < W && identity; ++c) identity = col_mid_[c] == c;
  col_identity_ = identity && int(lut_soa_[0].size()) == W * H;
  if (identity) {
    col_okm_.resize(W);
    for (int c = 0; c < W; ++c) col_okm_[c] = col_ok_[c] ? -1 : 0;
  }
  auto ring_pass4 = [&](int u, Candidates& cs) {
    using namespace simd;
    const size_t row = size_t(u) * W;
    float *cx = cs.x.data(), *cy = cs.y.data(), *cz = cs.z.data(), *cr = cs.range.data();
    int32_t* cp = cs.pixel.data();
    const float *dx = lut_soa_[0].data() + row, *dy = lut_soa_[1].data() + row, *dz = lut_soa_[2].data() + row;
    const float *ox = lut_soa_[3].data() + row, *oy = lut_soa_[4].data() + row, *oz = lut_soa_[5].data() + row;
    const v4i lo = splati(int32_t(std::min<uint32_t>(r_lo, 0x7fffffffu))), hi = splati(int32_t(std::min<uint32_t>(r_hi, 0x7fffffffu)));
    const v4f mm = splat(1e-3f);
    size_t m = cs.n;
    for (int c = 0; c < W; c += 4) {
      v4i ri;
      std::memcpy(&ri, rng + row + c, sizeof ri);
      v4i okm;
      std::memcpy(&okm, col_okm_.data() + c, sizeof okm);
      // Ranges are 20-bit (OS-1), far below 2^31: compared as signed integers; larger values fail the gate
      // only if r_hi is below them, which the clamp to 2^31-1 keeps (a negative int is < lo).
      const int in = movemask((ri >= lo) & (ri <= hi) & okm);
      if (in == 0) continue;
      const v4f fr = __builtin_convertvector(ri, v4f);
      v4f x = load(dx + c) * fr + load(ox + c), y = load(dy + c) * fr + load(oy + c), z = load(dz + c) * fr + load(oz + c);
      if (deskew) {
        const auto R = [&](int e) { return load(rot_il + size_t(c / 8) * 72 + e * 8 + c % 8); };
        const v4f X = R(0) * x + R(1) * y + R(2) * z, Y = R(3) * x + R(4) * y + R(5) * z, Z = R(6) * x + R(7) * y + R(8) * z;
        x = X;
        y = Y;
        z = Z;
      }
      const v4f rm = fr * mm;
      const int32_t pix0 = int32_t(row + c);
      if (in == 15) {
        store(cx + m, x);
        store(cy + m, y);
        store(cz + m, z);
        store(cr + m, rm);
        store(cp + m, v4i{pix0, pix0 + 1, pix0 + 2, pix0 + 3});
        m += 4;
        continue;
      }
      for (int l = 0; l < 4; ++l) {
        cx[m] = x[l];
        cy[m] = y[l];
        cz[m] = z[l];
        cr[m] = rm[l];
        cp[m] = pix0 + l;
        m += size_t((in >> l) & 1);
      }
    }
    cs.n = m;
    cs.ring_start.push_back(int32_t(m));
  };
  auto ring_pass1 = [&](int u, Candidates& cs) {
    const size_t row = size_t(u) * W;
    float *cx = cs.x.data(), *cy = cs.y.data(), *cz = cs.z.data(), *cr = cs.range.data();
    int32_t* cp = cs.pixel.data();
    size_t m = cs.n;
    for (int c = 0; c < W; ++c) {
      const size_t i = row + c;
      const uint32_t r = rng[i];
      const bool ok = (r >= r_lo) & (r <= r_hi) & (col_ok_[c] != 0);
      const size_t k = 3 * (row + col_mid_[c]);
      const float fr = float(r);
      Eigen::Vector3f p(dir[k] * fr + off[k], dir[k + 1] * fr + off[k + 1], dir[k + 2] * fr + off[k + 2]);
      if (deskew) p = deskew_.rotation_at(c) * p;
      cx[m] = p.x();
      cy[m] = p.y();
      cz[m] = p.z();
      cr[m] = fr * 1e-3f;
      cp[m] = int32_t(i);
      m += size_t(ok);
    }
    cs.n = m;
    cs.ring_start.push_back(int32_t(m));
  };
#if FPLOC_PREP_WIDE
  const bool wide8 = identity && W % 8 == 0 && kern::wide();
  const bool all_ok = std::all_of(col_ok_.begin(), col_ok_.end(), [](uint8_t o) { return o != 0; });
  auto ring_pass8w = [&](int u, int next_u, Candidates& cs) {
    const size_t row = size_t(u) * W;
    const float* lut[6];
    for (int e = 0; e < 6; ++e) lut[e] = lut_soa_[e].data() + row;
    // (the row's z is taken before the rotation: the same floats as the table's)
    const bool zrow = !std::isnan(row_z_[size_t(u)][0]);
    // (the measured z not stored where wall selection computes it again from the candidate's range: the row's z
    // one value and the range giving the mm back exactly)
    float* const raw[3] = {cs.raw_x.data(), cs.raw_y.data(), zrow && raw_z_from_range_ ? nullptr : cs.raw_z.data()};
    cs.n = ring_pass8(rng + row, all_ok ? nullptr : col_okm_.data(), lut, zrow ? row_z_[size_t(u)].data() : nullptr,
                      rot_il, deskew ? raw : nullptr,
                      next_u >= 0 ? rng + size_t(next_u) * W : nullptr, W, int32_t(std::min<uint32_t>(r_lo, 0x7fffffffu)),
                      int32_t(std::min<uint32_t>(r_hi, 0x7fffffffu)), int32_t(row), cs.x.data(), cs.y.data(), cs.z.data(),
                      cs.range.data(), cs.pixel.data(), cs.n);
    cs.ring_start.push_back(int32_t(cs.n));
  };
#else
  const bool wide8 = false;
  auto ring_pass8w = [&](int, int, Candidates&) {};
#endif
  auto ring_pass = [&](int u, int next_u, Candidates& cs) {
    wide8 ? ring_pass8w(u, next_u, cs) : identity ? ring_pass4(u, cs) : ring_pass1(u, cs);
  };
  const int half = H / 2;
  for (auto [cs, rings] : {std::pair{&upper_, half}, std::pair{&lower_, half}, std::pair{&middle_, H % 2}}) {
    // (+ 8: wall selection's eight-lane loops read up to 7 entries past a ring's end)
    const size_t cap = size_t(rings) * W + 2 * Candidates::kLanes;
    for (auto* v : {&cs->x, &cs->y, &cs->z, &cs->range}) v->resize(cap);
    // The returns as measured beside the de-skewed ones (the wall points), written by the eight-lane pass.
    cs->has_raw = deskew && wide8;
    if (cs->has_raw)
      for (auto* v : {&cs->raw_x, &cs->raw_y, &cs->raw_z}) v->resize(cap);
    cs->pixel.resize(cap);
    cs->p.clear();
    cs->n = 0;
    cs->ring_start.assign(1, 0);
    cs->width = W;
    cs->seed_rings = scale_.seed_rings;
    cs->start_stride = scale_.start_stride;
    cs->final_stride = scale_.final_stride;
  }
  // (each with the row after it, whose ranges the eight-lane pass prefetches)
  for (int k = 0; k < half; ++k) ring_pass(ring_order_[k], k + 1 < half ? ring_order_[k + 1] : ring_order_[H - 1], upper_);
  for (int k = 0; k < half; ++k)
    ring_pass(ring_order_[H - 1 - k], k + 1 < half ? ring_order_[H - 2 - k] : H % 2 == 1 ? ring_order_[half] : -1, lower_);
  if (H % 2 == 1) ring_pass(ring_order_[half], -1, middle_);
  for (Candidates* cs : {&upper_, &lower_, &middle_})
    for (auto* v : {&cs->x, &cs->y, &cs->z}) std::fill(v->begin() + cs->n, v->begin() + cs->n + Candidates::kLanes, std::numeric_limits<float>::quiet_NaN());
  // The plane fits' candidates' bounding boxes per block (the band and the plane quality skip blocks by them).
  for (Candidates* cs : {&upper_, &lower_}) {
    cs->box_stride = (cs->n + Candidates::kBoxPoints - 1) / Candidates::kBoxPoints;
    if (cs->box.size() < 6 * cs->box_stride) cs->box.resize(6 * cs->box_stride);
    cs->box_r = ck::available() && kern::wide()
                    ? ck::boxes(cs->x.data(), cs->y.data(), cs->z.data(), cs->n, cs->box.data(), cs->box_stride)
                    : ck::boxes_scalar(cs->x.data(), cs->y.data(), cs->z.data(), cs->n, cs->box.data(), cs->box_stride);
    cs->box_n = cs->n;
  }
  const size_t valid = upper_.n + lower_.n + middle_.n;
  if (valid == 0) return fail(SegStatus::kEmpty, "no valid returns in the scan");
  return true;
}

const std::vector<Eigen::Vector3f>& Segmenter::points() const {
  points_.assign(size_t(out_.height) * out_.width, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  for (const Candidates* cs : {&upper_, &lower_, &middle_})
    for (size_t j = 0; j < cs->n; ++j) points_[size_t(cs->pixel[j])] = cs->point(j);
  return points_;
}

}  // namespace fploc::seg
