#include "fploc/features/features.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fploc::feat {

FeatureExtractor::FeatureExtractor(FeatureConfig cfg) : cfg_(cfg) {}

const FeatureFrame& FeatureExtractor::process(const seg::Segmentation& seg) {
  // Cleared, not re-created: the arrays keep their capacity from scan to scan.
  for (auto* v : {&out_.x, &out_.y, &out_.t}) v->clear();
  out_.kind.clear();
  out_.group.clear();
  out_.source.clear();
  out_.num_groups = 0;
  const FeatureStatus status = extract(seg);
  std::vector<Feature2> points = std::move(frame_.points);
  points.clear();
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
  const size_t n = out_.x.size();
  frame_.points.reserve(n);
  source_.clear();
  source_.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(out_.x[i]) || !std::isfinite(out_.y[i])) continue;
    Feature2 p;
    p.p = {double(out_.x[i]), double(out_.y[i])};
    p.kind = FeatureKind(out_.kind[i]);
    p.group = out_.group[i];
    p.t = out_.t[i];
    frame_.points.push_back(p);
    source_.push_back(out_.source[i]);
  }
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
  size_t b = 0;
  for (size_t i = 1; i <= n; ++i) {
    if (i == n || w.ring[i] != w.ring[b]) {
      if (w.ring[b] % ring_step_ == 0) ring(seg, b, i);
      b = i;
    }
  }
  return out_.x.size() < 30 ? FeatureStatus::kFewFeatures : FeatureStatus::kOk;
}

void FeatureExtractor::ring(const seg::Segmentation& seg, size_t begin, size_t end) {
  const auto& w = seg.wall;
  const int n = int(end - begin);
  const int hw = std::max(1, cfg_.half_window);
  if (n < 2 * hw + 1) return;
  const float *X = w.x.data() + begin, *Y = w.y.data() + begin, *Z = w.z.data() + begin;
  const float* R = w.range.data() + begin;
  const int16_t* C = w.column.data() + begin;

  // Not cleared: curv_ is written wherever it is read ([hw, n-hw)), ok_ is written everywhere below.
  curv_.resize(n);
  ok_.resize(n);
  picked_.assign(n, 0);
  // One pass (issue 14 item 7; the same values as the earlier separate passes): the break prefix (brk[j] =
  // number of column gaps among the first j neighbour pairs), the window sums by prefix sums (double: ring
  // coordinates reach ~100 m; sum(X_j - X_i) = S - (2hw+1) X_i), and, hw points behind the prefix, the
  // smoothness, the window/range test and the parallel-surface test of point i = j - hw. The prefix sums
  // are a chain of dependent additions; the smoothness of earlier points fills the cycles between them.
  // Occlusion boundaries (rare) are only recorded here and applied after the pass (the rules only clear
  // ok_, so the order does not matter).
  auto& brk = brk_;
  brk.resize(n + 1);
  brk[0] = 0;
  const int gap = cfg_.max_column_gap;
  const float rmin = float(cfg_.min_range_m), rmax = float(cfg_.max_range_m);
  const float occ = float(cfg_.occlusion_ratio), par = float(cfg_.parallel_ratio);
  prex_.resize(size_t(n) + 1);
  prey_.resize(size_t(n) + 1);
  prez_.resize(size_t(n) + 1);
  double *px = prex_.data(), *py = prey_.data(), *pz = prez_.data();
  px[0] = py[0] = pz[0] = 0.0;
  const double win = double(2 * hw + 1);
  const float den = float(2 * hw);
  float* curv = curv_.data();
  uint8_t* ok = ok_.data();
  occ_.clear();
  auto prefix = [&](int j) __attribute__((always_inline)) {
    const int step = j + 1 < n ? C[j + 1] - C[j] : gap + 1;
    brk[j + 1] = brk[j] + int(step > gap);
    px[j + 1] = px[j] + double(X[j]);
    py[j + 1] = py[j] + double(Y[j]);
    pz[j + 1] = pz[j] + double(Z[j]);
    // LOAM's unreliable points, part 1: the far side of an occlusion boundary between neighbours j, j+1.
    if (j + 1 < n) {
      const float a = R[j], c = R[j + 1];
      const float mn = a < c ? a : c;  // minss, no branch
      if ((step <= gap) & (std::abs(a - c) > occ * mn)) occ_.push_back(a > c ? -(j + 1) : j + 1);
    }
  };
  auto point = [&](int i) {
    // All of i-hw .. i+hw connected: no break between i-hw and i+hw-1. LOAM's unreliable points, part 2:
    // surfaces parallel to the beam (range jumps to both sides).
    const float ri = R[i];
    const bool okw = (brk[i + hw] == brk[i - hw]) & !(ri < rmin) & !(ri > rmax);
    const bool parallel = (std::abs(R[i - 1] - ri) > par * ri) & (std::abs(R[i + 1] - ri) > par * ri);
    const double dx = (px[i + hw + 1] - px[i - hw]) - win * double(X[i]);
    const double dy = (py[i + hw + 1] - py[i - hw]) - win * double(Y[i]);
    const double dz = (pz[i + hw + 1] - pz[i - hw]) - win * double(Z[i]);
    curv[i] = float(std::sqrt(dx * dx + dy * dy + dz * dz)) / (den * ri);  // LOAM's c = |sum(X_j - X_i)| / (|S| |X_i|)
    ok[i] = uint8_t(okw & !parallel);
  };
  for (int i = 0; i < hw; ++i) ok[i] = 0;
  for (int i = n - hw; i < n; ++i) ok[i] = 0;
  for (int j = 0; j < 2 * hw; ++j) prefix(j);
  int j = 2 * hw;
#if defined(__SSE2__)
  // Four points at a time: two sqrtpd (the same correctly rounded roots as one at a time) and one divps
  // (the same quotients): the divider, shared by square roots and divisions, was the bottleneck.
  const __m128d w2 = _mm_set1_pd(win);
  const __m128 den4 = _mm_set1_ps(den);
  auto ld = [](const double* p) { return _mm_loadu_pd(p); };
  auto cvt2 = [](const float* p) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)))); };
  auto norm2 = [&](int i) {  // |sum(X_j - X_i)| of points i, i+1
    const __m128d dx = _mm_sub_pd(_mm_sub_pd(ld(px + i + hw + 1), ld(px + i - hw)), _mm_mul_pd(w2, cvt2(X + i)));
    const __m128d dy = _mm_sub_pd(_mm_sub_pd(ld(py + i + hw + 1), ld(py + i - hw)), _mm_mul_pd(w2, cvt2(Y + i)));
    const __m128d dz = _mm_sub_pd(_mm_sub_pd(ld(pz + i + hw + 1), ld(pz + i - hw)), _mm_mul_pd(w2, cvt2(Z + i)));
    return _mm_cvtpd_ps(_mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz))));
  };
  for (; j + 4 <= n; j += 4) {
    for (int q = j; q < j + 4; ++q) prefix(q);
    const int i = j - hw;  // points i .. i+3 need the prefix up to i + 3 + hw + 1 = j + 4
    const __m128 nrm = _mm_movelh_ps(norm2(i), norm2(i + 2));
    _mm_storeu_ps(curv + i, _mm_div_ps(nrm, _mm_mul_ps(den4, _mm_loadu_ps(R + i))));
    for (int l = 0; l < 4; ++l) {
      const int q = i + l;
      const float rq = R[q];
      const bool okw = (brk[q + hw] == brk[q - hw]) & !(rq < rmin) & !(rq > rmax);
      const bool parallel = (std::abs(R[q - 1] - rq) > par * rq) & (std::abs(R[q + 1] - rq) > par * rq);
      ok[q] = uint8_t(okw & !parallel);
    }
  }
#endif
  for (; j < n; ++j) {
    prefix(j);
    point(j - hw);  // needs the prefix up to j + 1 = i + hw + 1
  }
  for (const int e : occ_) {  // +(j+1): the near side is j (clear j+1 .. j+hw); -(j+1): clear j-hw+1 .. j
    if (e < 0) {
      const int j = -e - 1;
      for (int k = std::max(0, j - hw + 1); k <= j; ++k) ok[k] = 0;
    } else {
      const int j = e - 1;
      for (int k = j + 1; k <= std::min(n - 1, j + hw); ++k) ok[k] = 0;
    }
  }

  // Per-sector selection (sectors split the ring's points evenly, as LOAM does).
  sel_.clear();
  auto& kind_of = kind_;
  kind_of.resize(n);  // read only at the picks, which set it
  const int S = std::max(1, cfg_.sectors);
  const float cthr = float(cfg_.corner_threshold), sthr = float(cfg_.surface_threshold);
  const int max_corners = int(std::lround(cfg_.max_corners_per_sector * limit_scale_));
  const int max_surfaces = int(std::lround(cfg_.max_surfaces_per_sector * limit_scale_));
  for (int s = 0; s < S; ++s) {
    const int sb = hw + (n - 2 * hw) * s / S, se = hw + (n - 2 * hw) * (s + 1) / S;
    if (se <= sb) continue;
    // Corners: the sharpest candidate that no earlier pick suppressed, max_corners_per_sector times (the
    // same picks as walking the candidates sorted by decreasing c, ties by index; a branch-free scan per
    // pick instead of a sort, which mispredicted on every comparison). Candidates are collected without
    // a data-dependent branch too.
    // Corner (c > corner threshold) and surface (c < surface threshold) candidates in one pass. Surface
    // candidates a corner pick suppresses are skipped when walking them (the same picks as leaving them out).
    order_.resize(size_t(se - sb));
    surf_.resize(size_t(se - sb));
    // The first corner pick is found in the same pass (picked_ holds only the earlier sectors' picks then).
    size_t m = 0, ms = 0;
    int best0 = -1;
    float bv0 = -std::numeric_limits<float>::infinity();
    for (int i = sb; i < se; ++i) {
      const float ci = curv_[i];
      order_[m] = i;
      surf_[ms] = i;
      const bool corner = ok_[i] & uint8_t(ci > cthr);
      m += size_t(corner);
      ms += size_t(ok_[i] & uint8_t(ci < sthr));
      const bool take = corner & !picked_[i] & (ci > bv0);
      bv0 = take ? ci : bv0;
      best0 = take ? i : best0;
    }
    for (int corners = 0; corners < max_corners; ++corners) {
      int best = corners == 0 ? best0 : -1;
      float bv = -std::numeric_limits<float>::infinity();
      for (size_t j = 0; corners > 0 && j < m; ++j) {
        const int i = order_[j];
        const bool take = !picked_[i] & (curv_[i] > bv);
        bv = take ? curv_[i] : bv;
        best = take ? i : best;
      }
      if (best < 0) break;
      kind_of[best] = kCorner;
      sel_.push_back(best);
      for (int k = std::max(0, best - hw); k <= std::min(n - 1, best + hw); ++k) picked_[k] = 1;
    }
    // Surface candidates: only the smoothest few need ordering (partial sort, widened if the spacing
    // rule rejects too many).
    surf_.resize(ms);
    auto less = [&](int a, int b) { return curv_[a] < curv_[b] || (curv_[a] == curv_[b] && a < b); };
    size_t sorted = 0;
    int surfaces = 0;
    for (size_t j = 0; j < surf_.size() && surfaces < max_surfaces; ++j) {
      if (j == sorted) {
        // The next k smallest in order: selection then a sort of those k (the order is total, so the same
        // elements in the same order as a partial sort).
        const size_t k = std::min(surf_.size(), std::max<size_t>(sorted * 2, size_t(2 * max_surfaces)));
        if (k < surf_.size()) std::nth_element(surf_.begin() + sorted, surf_.begin() + k, surf_.end(), less);
        std::sort(surf_.begin() + sorted, surf_.begin() + k, less);
        sorted = k;
      }
      const int i = surf_[j];
      if (picked_[i]) continue;
      kind_of[i] = kSurface;
      sel_.push_back(i);
      ++surfaces;
      for (int k = std::max(0, i - cfg_.surface_spacing); k <= std::min(n - 1, i + cfg_.surface_spacing); ++k)
        picked_[k] = 1;
    }
  }

  // Emit in column order and group surface runs between corner anchors (or gaps) by PCA.
  std::vector<int> run;
  const size_t first_out = out_.x.size();
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
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
      const double l0 = std::max(es.eigenvalues()[0], 0.0), l1 = es.eigenvalues()[1];
      if (std::sqrt(l0) <= cfg_.line_max_rms_m && l1 >= cfg_.line_min_ratio * std::max(l0, 1e-12)) {
        const int32_t g = out_.num_groups++;
        for (int o : run) out_.group[o] = g;
      }
    }
    run.clear();
  };
  std::sort(sel_.begin(), sel_.end());  // the picks in column order (not a scan of all n points)
  for (const int i : sel_) {
    const size_t src = begin + i;
    const int o = int(out_.x.size());
    const Eigen::Vector3f q = R_ * Eigen::Vector3f(w.x[src], w.y[src], w.z[src]);
    out_.x.push_back(q.x());
    out_.y.push_back(q.y());
    out_.kind.push_back(kind_of[i]);
    out_.group.push_back(-1);
    out_.t.push_back(w.t.size() == w.x.size() ? w.t[src] : 0.f);
    out_.source.push_back(int32_t(src));
    if (kind_of[i] == kCorner) {
      close_run();
      continue;
    }
    if (!run.empty()) {
      const int p = run.back();
      const float dx = out_.x[o] - out_.x[p], dy = out_.y[o] - out_.y[p];
      if (dx * dx + dy * dy > float(cfg_.group_max_gap_m * cfg_.group_max_gap_m)) close_run();
    }
    run.push_back(o);
  }
  close_run();
  (void)first_out;
}

}  // namespace fploc::feat
