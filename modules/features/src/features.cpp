#include "fploc/features/features.h"

#include "smoothness.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fploc::feat {

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
// The values a suppressed entry gets (picked, corner c), eight of each.
constexpr uint8_t kOnes8[8] = {1, 1, 1, 1, 1, 1, 1, 1};
constexpr float kNegInf8[8] = {-kInf, -kInf, -kInf, -kInf, -kInf, -kInf, -kInf, -kInf};

// The end of the run of equal values that starts at b (one ring of the ring-major wall points).
size_t run_end(const int16_t* v, size_t b, size_t n) {
  size_t i = b + 1;
#if defined(__SSE2__)
  const __m128i r = _mm_set1_epi16(v[b]);
  for (; i + 8 <= n; i += 8) {
    const int eq = _mm_movemask_epi8(_mm_cmpeq_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(v + i)), r));
    if (eq != 0xffff) return i + size_t(__builtin_ctz(unsigned(~eq & 0xffff)) / 2);
  }
#endif
  while (i < n && v[i] == v[b]) ++i;
  return i;
}

// Bits of a non-NaN float whose unsigned order is the float order (-0 taken as +0, equal as floats).
inline uint32_t order_bits(float f) {
  f += 0.f;  // -0 -> +0
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u & 0x80000000u ? ~u : u | 0x80000000u;
}

}  // namespace

FeatureExtractor::FeatureExtractor(FeatureConfig cfg) : cfg_(cfg) {}

const FeatureFrame& FeatureExtractor::process(const seg::Segmentation& seg) {
  // Emptied, not cleared: the arrays keep their size and capacity from scan to scan (Picked).
  out_.n = 0;
  out_.num_groups = 0;
  const FeatureStatus status = extract(seg);
  // (the last frame's points keep their entries: sized to this frame's below, only the entries past the last
  // frame's count are constructed; every entry kept is written)
  std::vector<Feature2> points = std::move(frame_.points);
  frame_ = FeatureFrame{};
  frame_.points = std::move(points);
  frame_.utime = seg.utime;
  frame_.scan_seq = seg.seq;
  frame_.status = status;
  frame_.roll = seg.roll;
  frame_.pitch = seg.pitch;
  frame_.z = seg.z;
  frame_.roll_pitch_sigma = seg.roll_pitch_sigma;
  frame_.z_sigma = seg.z_sigma;
  frame_.attitude_t = seg.attitude_t;
  frame_.num_groups = out_.num_groups;
  const size_t n = out_.n;
  // (sized for every point, written through plain pointers, then cut to the finite ones: no per-point
  // capacity check and end-pointer update in memory)
  frame_.points.resize(n);
  source_.resize(n);
  Feature2* fp = frame_.points.data();
  int32_t* sp = source_.data();
  const float *ox = out_.x.data(), *oy = out_.y.data(), *ot = out_.t.data();
  const int8_t* ok = out_.kind.data();
  const int32_t *og = out_.group.data(), *os = out_.source.data();
  size_t m = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(ox[i]) || !std::isfinite(oy[i])) continue;
    Feature2& p = fp[m];
    p.p = {double(ox[i]), double(oy[i])};
    p.kind = FeatureKind(ok[i]);
    p.group = og[i];
    p.t = ot[i];
    sp[m] = os[i];
    ++m;
  }
  frame_.points.resize(m);
  source_.resize(m);
  return frame_;
}

FeatureStatus FeatureExtractor::extract(const seg::Segmentation& seg) {
  // An unusable scan upstream (bad or empty input: no planes, no wall points) is passed on as such.
  if (seg.status == seg::SegStatus::kBadInput || seg.status == seg::SegStatus::kEmpty) return FeatureStatus::kBadInput;
  const auto& w = seg.wall;
  const size_t n = w.x.size();
  if (w.y.size() != n || w.z.size() != n || w.range.size() != n || w.ring.size() != n || w.column.size() != n ||
      !std::isfinite(seg.roll) || !std::isfinite(seg.pitch))
    return FeatureStatus::kBadInput;
  // Gravity compensation: p_level = Ry(pitch) Rx(roll) p_sensor (yaw stays in the sensor frame); applied
  // to the selected features only.
  R_ = (Eigen::AngleAxisf(float(seg.pitch), Eigen::Vector3f::UnitY()) *
        Eigen::AngleAxisf(float(seg.roll), Eigen::Vector3f::UnitX()))
           .toRotationMatrix();
  // Beam pattern (issue 13 item 2): the per-ring limits are the paper's for 64 rings. A denser sensor uses
  // every ring_step-th ring (the same rings' density per degree of elevation, the same work); a sparser one
  // picks limit_scale times more per ring. Both 1 for 64 rings.
  const int H = std::max(1, seg.height);
  ring_step_ = std::max(1, int(std::lround(double(H) / kRefRings)));
  limit_scale_ = std::max(1.0, double(kRefRings) / H);
  // Per column, the farthest vertical structure (column_front_m): the second-farthest levelled horizontal range.
  far1_.clear();
  far2_.clear();
  level_range_.clear();
  if (cfg_.column_front_m > 0) {
    int width = std::max<int>(0, seg.width);
    for (size_t i = 0; i < n; ++i) width = std::max(width, int(w.column[i]) + 1);
    far1_.assign(size_t(width), 0.f);
    far2_.assign(size_t(width), 0.f);
    level_range_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f q = R_ * Eigen::Vector3f(w.x[i], w.y[i], w.z[i]);
      const float r = level_range_[i] = std::sqrt(q.x() * q.x() + q.y() * q.y());
      if (w.column[i] < 0 || !std::isfinite(r)) continue;
      float &a = far1_[size_t(w.column[i])], &b = far2_[size_t(w.column[i])];
      if (r > a) b = a, a = r;
      else if (r > b) b = r;
    }
  }
  // Height as evidence (high_band_m): the low points of a frame with enough high ones, unless on a high surface.
  low_.clear();
  if (cfg_.high_band_m > 0 && std::isfinite(seg.z) && seg.z_sigma < kZUnknownFromSigmaM) {
    const float band = float(cfg_.high_band_m - seg.z), same = float(cfg_.high_same_surface_m);
    int width = std::max<int>(0, seg.width);
    for (size_t i = 0; i < n; ++i) width = std::max(width, int(w.column[i]) + 1);
    near_high_.assign(size_t(width), kInf);
    low_.assign(n, 0);
    int high = 0;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f q = R_ * Eigen::Vector3f(w.x[i], w.y[i], w.z[i]);
      if (!(q.z() >= band)) {
        low_[i] = 1;
        continue;
      }
      const float r = std::sqrt(q.x() * q.x() + q.y() * q.y());
      if (!std::isfinite(r)) continue;
      ++high;
      if (w.column[i] >= 0) near_high_[size_t(w.column[i])] = std::min(near_high_[size_t(w.column[i])], r);
    }
    if (high < cfg_.high_min_points) {
      low_.clear();
    } else if (same > 0 || cfg_.high_keep_unseen) {
      for (size_t i = 0; i < n; ++i) {
        if (!low_[i] || w.column[i] < 0) continue;
        const float h = near_high_[size_t(w.column[i])];
        if (h == kInf) {
          if (cfg_.high_keep_unseen) low_[i] = 0;
          continue;
        }
        const Eigen::Vector3f q = R_ * Eigen::Vector3f(w.x[i], w.y[i], w.z[i]);
        const float r = std::sqrt(q.x() * q.x() + q.y() * q.y());
        if (std::abs(r - h) <= same) low_[i] = 0;
      }
    }
  }
  for (size_t b = 0; b < n;) {
    const size_t e = run_end(w.ring.data(), b, n);
    if (w.ring[b] % ring_step_ == 0) ring(seg, b, e);
    b = e;
  }
  return out_.n < 30 ? FeatureStatus::kFewFeatures : FeatureStatus::kOk;
}


void FeatureExtractor::ring(const seg::Segmentation& seg, size_t begin, size_t end) {
  const auto& w = seg.wall;
  const int n = int(end - begin);
  const int hw = std::max(1, cfg_.half_window);
  if (n < 2 * hw + 1) return;

  // Smoothness and candidates of every point (src/smoothness.h: vectorised, in float).
  const int nb = (n + 7) / 8;
  corner_c_.resize(size_t(nb) * 8);
  surface_c_.resize(size_t(nb) * 8);
  surface_.assign(size_t(n) / 64 + 2, 0);
  picked_.assign(size_t(n), 0);
  occ_.clear();
  // The times are read only for the picks, after this ring's pass: fetched now (every line of the ring's
  // times, which nothing else reads).
  if (w.t.size() == w.x.size())
    for (size_t k = begin; k < end; k += 16) __builtin_prefetch(w.t.data() + k);
  const detail::RingIn in{w.x.data() + begin, w.y.data() + begin, w.z.data() + begin, w.range.data() + begin,
                          w.column.data() + begin, n};
  const detail::RingRules rules{hw, cfg_.max_column_gap, float(cfg_.min_range_m), float(cfg_.max_range_m),
                                float(cfg_.occlusion_ratio), float(cfg_.parallel_ratio),
                                float(cfg_.corner_threshold), float(cfg_.surface_threshold)};
  detail::RingScratch scratch{ring_w_, ring_brk_};
  float* corner_c = corner_c_.data();  // q = c^2 of corner candidates, -inf elsewhere
  const float* sc = surface_c_.data();
  const uint64_t* sk = surface_.data();
  detail::smoothness(in, rules, scratch, corner_c, surface_.data(), surface_c_.data(), occ_);
  for (int k = 0; k < hw; ++k) corner_c[k] = -kInf;  // no window: no candidate
  for (int k = n - hw; k < nb * 8; ++k) corner_c[k] = -kInf;
  uint8_t* picked = picked_.data();
  // Taking points a..b out: no later corner or surface pick there (a pick's neighbours, occlusions).
  // (stored in blocks of 8 or 4, the last block ending at b: overlapping blocks write the same values, so the
  // same entries a..b are set, with fewer stores than one per entry; inlined at its five calls: a call per pick
  // cost more than its stores)
  auto suppress = [&](int a, int b) __attribute__((always_inline)) {
    a = std::max(0, a);
    b = std::min(n - 1, b);
    const int len = b - a + 1;
    if (len >= 8) {
      // (a corner's 2 hw + 1 = 11 entries: the blocks at a and at b - 7, no loop)
      std::memcpy(picked + a, kOnes8, 8);
      std::memcpy(corner_c + a, kNegInf8, 32);
      for (int k = a + 8; k < b - 7; k += 8) {
        std::memcpy(picked + k, kOnes8, 8);
        std::memcpy(corner_c + k, kNegInf8, 32);
      }
      std::memcpy(picked + b - 7, kOnes8, 8);
      std::memcpy(corner_c + b - 7, kNegInf8, 32);
    } else if (len >= 4) {
      std::memcpy(picked + a, kOnes8, 4);
      std::memcpy(corner_c + a, kNegInf8, 16);
      std::memcpy(picked + b - 3, kOnes8, 4);
      std::memcpy(corner_c + b - 3, kNegInf8, 16);
    } else {
      for (int k = a; k <= b; ++k) {
        picked[k] = 1;
        corner_c[k] = -kInf;
      }
    }
  };
  for (const int e : occ_) {  // +(j+1): the near side is j (j+1 .. j+hw out); -(j+1): j-hw+1 .. j out
    if (e < 0)
      suppress(-e - 1 - hw + 1, -e - 1);
    else
      suppress(e, e - 1 + hw);
  }
  // Points in front of a farther vertical structure of their column (column_front_m): no features.
  if (!far2_.empty()) {
    const float m = float(cfg_.column_front_m), ratio = float(cfg_.column_front_ratio);
    for (int k = 0; k < n; ++k) {
      const size_t i = begin + size_t(k);
      const int c = w.column[i];
      if (c < 0 || size_t(c) >= far2_.size()) continue;
      const float f = far2_[size_t(c)];
      if (f > 0 && level_range_[i] < f - m - ratio * f) suppress(k, k);
    }
  }
  // Low points of a frame with enough high ones (high_band_m): no features.
  if (!low_.empty())
    for (int k = 0; k < n; ++k)
      if (low_[begin + size_t(k)]) suppress(k, k);

  // Per-sector selection (sectors split the ring's points evenly, as LOAM does): the sharpest corner
  // candidates that no earlier pick suppressed (the first index among equal q = c^2), then the smoothest surface
  // candidates, walked in the order (q, index): the plain rules' picks.
  // The picks as bits (points in column order without a sort): bit i of feat, and of corner for a corner.
  const size_t words = size_t(n) / 64 + 1;
  pick_bits_.assign(2 * words, 0);
  uint64_t *feat = pick_bits_.data(), *corner_bit = feat + words;
  auto pick = [&](int i, bool corner) {
    feat[i >> 6] |= uint64_t(1) << (i & 63);
    if (corner) corner_bit[i >> 6] |= uint64_t(1) << (i & 63);
  };
  const int S = std::max(1, cfg_.sectors);
  const int max_corners = int(std::lround(cfg_.max_corners_per_sector * limit_scale_));
  const int max_surfaces = int(std::lround(cfg_.max_surfaces_per_sector * limit_scale_));
  // A sector's surface candidates and their sort keys, written through plain pointers (at most n of each).
  if (surf_.size() < size_t(n)) surf_.resize(size_t(n));
  if (surf_keys_.size() < size_t(n)) surf_keys_.resize(size_t(n));
  int* const cand = surf_.data();
  uint64_t* const keys = surf_keys_.data();
  for (int s = 0; s < S; ++s) {
    const int sb = hw + (n - 2 * hw) * s / S, se = hw + (n - 2 * hw) * (s + 1) / S;
    if (se <= sb) continue;
    for (int corners = 0; corners < max_corners; ++corners) {
      // The sharpest candidate: the first index with the largest q = c^2 (smoothness.h; one vector scan of the
      // sector: a sector is ~n/6 points, cheaper than keeping block maxima up to date).
      const int best = detail::first_argmax(corner_c, sb, se);
      if (best < 0) break;
      pick(best, true);
      suppress(best - hw, best + hw);
    }
    if (max_surfaces <= 0) continue;
    size_t nc = 0;
    for (int wb = sb >> 6; wb <= (se - 1) >> 6; ++wb) {  // the bits of [sb, se)
      uint64_t bits = sk[wb];
      if (wb == sb >> 6) bits &= ~uint64_t(0) << (sb & 63);
      if (wb == (se - 1) >> 6 && ((se - 1) & 63) < 63) bits &= (uint64_t(2) << ((se - 1) & 63)) - 1;
      while (bits) {
        const int i = (wb << 6) + __builtin_ctzll(bits);
        bits &= bits - 1;
        cand[nc] = i;
        nc += !picked[i];
      }
    }
    // When the sector's candidates are no more than its limit, every one that no other candidate's pick
    // can suppress (none within the spacing) is picked whatever the order: no sort for those.
    const int sp = cfg_.surface_spacing;
    if (int(nc) <= max_surfaces) {
      size_t m = 0;
      for (size_t k = 0; k < nc; ++k) {
        const int i = cand[k];
        const bool near = (k > 0 && i - cand[k - 1] <= sp) || (k + 1 < nc && cand[k + 1] - i <= sp);
        if (!near) {
          pick(i, false);
          suppress(i - sp, i + sp);
        } else {
          cand[m++] = i;
        }
      }
      nc = m;
    }
    // The others in the order (q, index), sorted as 64-bit keys: order_bits(q) above the index (q = c^2 before
    // the root, smoothness.h).
    for (size_t k = 0; k < nc; ++k) keys[k] = uint64_t(order_bits(sc[cand[k]])) << 32 | uint32_t(cand[k]);
    std::sort(keys, keys + nc);
    int surfaces = 0;  // (the direct picks above only happen when the limit cannot be reached)
    for (size_t k = 0; k < nc; ++k) {
      const int i = int(uint32_t(keys[k]));
      if (picked[i]) continue;
      pick(i, false);
      suppress(i - cfg_.surface_spacing, i + cfg_.surface_spacing);
      if (++surfaces == max_surfaces) break;
    }
  }

  // Emit in column order and group surface runs between corner anchors (or gaps) by PCA.
  auto& run = run_;
  run.clear();
  auto close_run = [&]() {
    if (int(run.size()) >= cfg_.min_group_points) {
      Eigen::Vector2d m = Eigen::Vector2d::Zero();
      for (int o : run) m += Eigen::Vector2d(out_.x[o], out_.y[o]);
      m /= double(run.size());
      Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
      for (int o : run) {
        const Eigen::Vector2d d = Eigen::Vector2d(out_.x[o], out_.y[o]) - m;
        C += d * d.transpose();
      }
      C /= double(run.size());
      // A line when sqrt(l0) <= rms and l1 >= ratio l0 (l0 <= l1 the eigenvalues, l0 clamped at 0 and 1e-12).
      // The test is monotone (harder as l0 grows or l1 shrinks), so the closed-form eigenvalues decide it
      // whenever it comes out the same at both ends of their error interval (+-1e-12 |C|, hundreds of times
      // the backward errors of either computation); otherwise Eigen's solver (the plain rules') decides.
      auto line = [&](double e0, double e1) {
        const double l0 = std::max(e0, 0.0);
        return std::sqrt(l0) <= cfg_.line_max_rms_m && e1 >= cfg_.line_min_ratio * std::max(l0, 1e-12);
      };
      const double a = C(0, 0), b = C(0, 1), c = C(1, 1);
      const double t = 0.5 * (a + c), h = 0.5 * (a - c), d = std::sqrt(h * h + b * b);
      const double e0 = t - d, e1 = t + d, tol = 1e-12 * (std::abs(a) + std::abs(b) + std::abs(c)) + 1e-300;
      // (monotone needs ratio >= 0; otherwise always the solver)
      const bool finite = std::isfinite(e0) && std::isfinite(e1) && cfg_.line_min_ratio >= 0;
      bool is_line = finite && line(e0 + tol, e1 - tol);
      if (!is_line && (!finite || line(e0 - tol, e1 + tol))) {
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
        is_line = line(es.eigenvalues()[0], es.eigenvalues()[1]);
      }
      if (is_line) {
        const int32_t g = out_.num_groups++;
        for (int o : run) out_.group[o] = g;
      }
    }
    run.clear();
  };
  sel_.clear();  // the picks in column order, as 2 * index + (1 for a corner)
  for (size_t q = 0; q < words; ++q)
    for (uint64_t b = feat[q]; b; b &= b - 1) {
      const int i = int(q * 64) + __builtin_ctzll(b);
      sel_.push_back(2 * i + int(corner_bit[q] >> (i & 63) & 1));
    }
  const bool has_t = w.t.size() == w.x.size();
  const float max_gap2 = float(cfg_.group_max_gap_m * cfg_.group_max_gap_m);
  // The picks' output first (independent iterations, written in place), then the runs.
  const size_t o0 = out_.n, m = sel_.size();
  if (out_.x.size() < o0 + m) {  // (grown only: every entry below o0 + m is written here)
    out_.x.resize(o0 + m);
    out_.y.resize(o0 + m);
    out_.kind.resize(o0 + m);
    out_.group.resize(o0 + m);
    out_.t.resize(o0 + m);
    out_.source.resize(o0 + m);
  }
  out_.n = o0 + m;
  {
    // (through plain pointers and a local rotation: a store of a kind, an int8_t, may alias anything, so the arrays'
    // and the rotation's members were loaded again after each pick's)
    // The rotation's first two rows as scalars: (R p).x() and .y() written out as Eigen sums them (its 3-term
    // redux: a0 + (a1 + a2)), the same floats bit for bit (the ReferenceEqual* tests, whose reference computes R p
    // with Eigen); Eigen's 3x3 product was an out-of-line call per pick here, and z was computed for nothing.
    const float r00 = R_(0, 0), r01 = R_(0, 1), r02 = R_(0, 2), r10 = R_(1, 0), r11 = R_(1, 1), r12 = R_(1, 2);
    const int* const sel = sel_.data();
    const float *const wx = w.x.data(), *const wy = w.y.data(), *const wz = w.z.data();
    const float* const wt = has_t ? w.t.data() : nullptr;
    float *const ox = out_.x.data(), *const oy = out_.y.data(), *const ot = out_.t.data();
    int8_t* const okind = out_.kind.data();
    int32_t *const ogroup = out_.group.data(), *const osource = out_.source.data();
    for (size_t k = 0; k < m; ++k) {
      const int code = sel[k];
      const size_t src = begin + size_t(code >> 1), o = o0 + k;
      const float px = wx[src], py = wy[src], pz = wz[src];
      ox[o] = r00 * px + (r01 * py + r02 * pz);
      oy[o] = r10 * px + (r11 * py + r12 * pz);
      okind[o] = code & 1 ? kCorner : kSurface;
      ogroup[o] = -1;  // (unclassified until a line group takes it, below)
      ot[o] = wt ? wt[src] : 0.f;
      osource[o] = int32_t(src);
    }
  }
  for (size_t k = 0; k < m; ++k) {
    const bool corner = sel_[k] & 1;
    const int o = int(o0 + k);
    if (corner) {
      close_run();
      continue;
    }
    if (!run.empty()) {
      const int p = run.back();
      const float dx = out_.x[o] - out_.x[p], dy = out_.y[o] - out_.y[p];
      if (dx * dx + dy * dy > max_gap2) close_run();
    }
    run.push_back(o);
  }
  close_run();
}

}  // namespace fploc::feat
