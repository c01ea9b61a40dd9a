// The feature extractor's rules written the plain way (test only): one point at a time, every smoothness
// computed on its own (its float definition, below), corner and surface candidates sorted (LOAM's order) and
// walked. The fast extractor must give the same frame, bit for
// bit (features_test ReferenceEqual*): it may skip work, never change a pick.
#pragma once
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <vector>

#include "fploc/features/features.h"

namespace fploc::feat::reference {

// The smoothness of point i of a ring (X, Y, Z the ring's arrays): c = |sum_j (X_j - X_i)| / |sum_j X_j|
// (LOAM's with the neighbours' range for the point's own, see src/smoothness.h), defined by its float
// computation (float_smoothness, written out here): the hw points before i and the hw points after i each
// added up in index order, S = A + B, d = S - 2hw X_i, one division, one root.
// smoothness_sq: c^2 before the root, q; the picks follow q's order (c's, but where two q round to the same c:
// src/smoothness.h), the thresholds apply to c.
inline float smoothness_sq(const float* X, const float* Y, const float* Z, int i, int hw) {
  float ax = 0, ay = 0, az = 0, bx = 0, by = 0, bz = 0;
  for (int q = 0; q < hw; ++q) {
    ax = q == 0 ? X[i - hw] : ax + X[i - hw + q];
    ay = q == 0 ? Y[i - hw] : ay + Y[i - hw + q];
    az = q == 0 ? Z[i - hw] : az + Z[i - hw + q];
    bx = q == 0 ? X[i + 1] : bx + X[i + 1 + q];
    by = q == 0 ? Y[i + 1] : by + Y[i + 1 + q];
    bz = q == 0 ? Z[i + 1] : bz + Z[i + 1 + q];
  }
  const float den = float(2 * hw);
  const float sx = ax + bx, sy = ay + by, sz = az + bz;
  const float dx = sx - den * X[i], dy = sy - den * Y[i], dz = sz - den * Z[i];
  return ((dx * dx + dy * dy) + dz * dz) / ((sx * sx + sy * sy) + sz * sz);
}
inline float smoothness(const float* X, const float* Y, const float* Z, int i, int hw) {
  return std::sqrt(smoothness_sq(X, Y, Z, i, hw));
}

struct Result {
  std::vector<Feature2> points;
  std::vector<int32_t> source;
  int32_t num_groups = 0;
  FeatureStatus status = FeatureStatus::kOk;
};

inline Result extract(const seg::Segmentation& seg, const FeatureConfig& cfg = {}) {
  Result res;
  if (seg.status == seg::SegStatus::kBadInput || seg.status == seg::SegStatus::kEmpty) {
    res.status = FeatureStatus::kBadInput;
    return res;
  }
  const auto& w = seg.wall;
  const size_t N = w.x.size();
  const Eigen::Matrix3f Rot = (Eigen::AngleAxisf(float(seg.pitch), Eigen::Vector3f::UnitY()) *
                               Eigen::AngleAxisf(float(seg.roll), Eigen::Vector3f::UnitX()))
                                  .toRotationMatrix();
  const int H = std::max(1, seg.height);
  const int ring_step = std::max(1, int(std::lround(double(H) / 64)));
  const double limit_scale = std::max(1.0, 64.0 / H);
  std::vector<float> ox, oy, ot;
  std::vector<int8_t> okind;
  std::vector<int32_t> ogroup, osrc;
  int32_t groups = 0;
  // The farthest vertical structure of each column (column_front_m): its second-farthest levelled horizontal range.
  auto level_range = [&](size_t i) {
    const Eigen::Vector3f q = Rot * Eigen::Vector3f(w.x[i], w.y[i], w.z[i]);
    return std::sqrt(q.x() * q.x() + q.y() * q.y());
  };
  std::vector<std::vector<float>> column_ranges;
  if (cfg.column_front_m > 0)
    for (size_t i = 0; i < N; ++i) {
      if (w.column[i] < 0) continue;
      if (size_t(w.column[i]) >= column_ranges.size()) column_ranges.resize(size_t(w.column[i]) + 1);
      const float r = level_range(i);
      if (std::isfinite(r)) column_ranges[size_t(w.column[i])].push_back(r);
    }
  auto in_front = [&](size_t i) {
    if (!(cfg.column_front_m > 0) || w.column[i] < 0) return false;
    std::vector<float> v = column_ranges[size_t(w.column[i])];
    if (v.size() < 2) return false;
    std::sort(v.begin(), v.end());
    const float f = v[v.size() - 2];
    return f > 0 && level_range(i) < f - float(cfg.column_front_m) - float(cfg.column_front_ratio) * f;
  };
  // Height as evidence (high_band_m): a low point of a frame with enough high ones, unless its column holds a high
  // point within high_same_surface_m of its levelled range.
  std::vector<bool> low(N, false);
  if (cfg.high_band_m > 0 && std::isfinite(seg.z) && seg.z_sigma < kZUnknownFromSigmaM) {
    auto height = [&](size_t i) { return (Rot * Eigen::Vector3f(w.x[i], w.y[i], w.z[i])).z(); };
    const float band = float(cfg.high_band_m - seg.z);
    int high = 0;
    for (size_t i = 0; i < N; ++i) high += height(i) >= band && std::isfinite(level_range(i));
    std::map<int, float> nearest;  // per column: the nearest high point's levelled range
    for (size_t i = 0; i < N; ++i)
      if (height(i) >= band && std::isfinite(level_range(i)) && w.column[i] >= 0) {
        auto it = nearest.emplace(w.column[i], level_range(i)).first;
        it->second = std::min(it->second, level_range(i));
      }
    if (high >= cfg.high_min_points)
      for (size_t i = 0; i < N; ++i) {
        if (height(i) >= band) continue;
        const auto it = nearest.find(w.column[i]);
        if (w.column[i] >= 0 && it == nearest.end() && cfg.high_keep_unseen) continue;  // no high point: kept
        low[i] = !(cfg.high_same_surface_m > 0 && w.column[i] >= 0 && it != nearest.end() &&
                   std::abs(level_range(i) - it->second) <= float(cfg.high_same_surface_m));
      }
  }
  auto ring = [&](size_t begin, size_t end) {
    const int n = int(end - begin), hw = std::max(1, cfg.half_window);
    if (n < 2 * hw + 1) return;
    const float *X = &w.x[begin], *Y = &w.y[begin], *Z = &w.z[begin], *R = &w.range[begin];
    const int16_t* C = &w.column[begin];
    std::vector<float> c(n, 0.f), q(n, 0.f);  // c and q = c^2 before the root
    std::vector<bool> ok(n, false), picked(n, false);
    for (int i = hw; i < n - hw; ++i) {
      bool connected = true;
      for (int j = i - hw; j < i + hw; ++j) connected = connected && C[j + 1] - C[j] <= cfg.max_column_gap;
      const float r = R[i];
      const bool in_range = !(r < float(cfg.min_range_m)) && !(r > float(cfg.max_range_m));
      const float par = float(cfg.parallel_ratio);
      const bool parallel = std::abs(R[i - 1] - r) > par * r && std::abs(R[i + 1] - r) > par * r;
      q[i] = smoothness_sq(X, Y, Z, i, hw);
      c[i] = std::sqrt(q[i]);
      ok[i] = connected && in_range && !parallel && !in_front(begin + size_t(i)) && !low[begin + size_t(i)];
    }
    for (int j = 0; j + 1 < n; ++j) {  // occlusion boundaries: clear hw points on the far side
      const float a = R[j], b = R[j + 1];
      if (C[j + 1] - C[j] > cfg.max_column_gap || !(std::abs(a - b) > float(cfg.occlusion_ratio) * std::min(a, b))) continue;
      if (a > b)
        for (int k = std::max(0, j - hw + 1); k <= j; ++k) ok[k] = false;
      else
        for (int k = j + 1; k <= std::min(n - 1, j + hw); ++k) ok[k] = false;
    }
    std::vector<int> sel;
    std::vector<int8_t> kind(n, 0);
    const int S = std::max(1, cfg.sectors);
    const int max_c = int(std::lround(cfg.max_corners_per_sector * limit_scale));
    const int max_s = int(std::lround(cfg.max_surfaces_per_sector * limit_scale));
    for (int s = 0; s < S; ++s) {
      const int sb = hw + (n - 2 * hw) * s / S, se = hw + (n - 2 * hw) * (s + 1) / S;
      std::vector<int> corners, surfaces;
      for (int i = sb; i < se; ++i) {
        if (ok[i] && c[i] > float(cfg.corner_threshold)) corners.push_back(i);
        if (ok[i] && c[i] < float(cfg.surface_threshold)) surfaces.push_back(i);
      }
      std::stable_sort(corners.begin(), corners.end(), [&](int a, int b) { return q[a] > q[b]; });
      int picks = 0;
      for (int i : corners) {
        if (picks >= max_c) break;
        if (picked[i]) continue;
        kind[i] = int8_t(FeatureKind::kCorner);
        sel.push_back(i);
        ++picks;
        for (int k = std::max(0, i - hw); k <= std::min(n - 1, i + hw); ++k) picked[k] = true;
      }
      std::stable_sort(surfaces.begin(), surfaces.end(), [&](int a, int b) { return q[a] < q[b]; });
      picks = 0;
      for (int i : surfaces) {
        if (picks >= max_s) break;
        if (picked[i]) continue;
        kind[i] = int8_t(FeatureKind::kSurface);
        sel.push_back(i);
        ++picks;
        for (int k = std::max(0, i - cfg.surface_spacing); k <= std::min(n - 1, i + cfg.surface_spacing); ++k)
          picked[k] = true;
      }
    }
    std::sort(sel.begin(), sel.end());
    std::vector<int> run;
    auto close_run = [&]() {
      if (int(run.size()) >= cfg.min_group_points) {
        Eigen::Vector2d m = Eigen::Vector2d::Zero();
        for (int o : run) m += Eigen::Vector2d(ox[o], oy[o]);
        m /= double(run.size());
        Eigen::Matrix2d Cv = Eigen::Matrix2d::Zero();
        for (int o : run) {
          const Eigen::Vector2d d = Eigen::Vector2d(ox[o], oy[o]) - m;
          Cv += d * d.transpose();
        }
        Cv /= double(run.size());
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(Cv);
        const double l0 = std::max(es.eigenvalues()[0], 0.0), l1 = es.eigenvalues()[1];
        if (std::sqrt(l0) <= cfg.line_max_rms_m && l1 >= cfg.line_min_ratio * std::max(l0, 1e-12)) {
          for (int o : run) ogroup[o] = groups;
          ++groups;
        }
      }
      run.clear();
    };
    for (int i : sel) {
      const size_t src = begin + size_t(i);
      const int o = int(ox.size());
      const Eigen::Vector3f q = Rot * Eigen::Vector3f(w.x[src], w.y[src], w.z[src]);
      ox.push_back(q.x());
      oy.push_back(q.y());
      okind.push_back(kind[i]);
      ogroup.push_back(-1);
      ot.push_back(w.t.size() == N ? w.t[src] : 0.f);
      osrc.push_back(int32_t(src));
      if (kind[i] == int8_t(FeatureKind::kCorner)) {
        close_run();
        continue;
      }
      if (!run.empty()) {
        const float dx = ox[o] - ox[run.back()], dy = oy[o] - oy[run.back()];
        if (dx * dx + dy * dy > float(cfg.group_max_gap_m * cfg.group_max_gap_m)) close_run();
      }
      run.push_back(o);
    }
    close_run();
  };
  size_t b = 0;
  for (size_t i = 1; i <= N; ++i)
    if (i == N || w.ring[i] != w.ring[b]) {
      if (w.ring[b] % ring_step == 0) ring(b, i);
      b = i;
    }
  res.status = ox.size() < 30 ? FeatureStatus::kFewFeatures : FeatureStatus::kOk;
  res.num_groups = groups;
  for (size_t i = 0; i < ox.size(); ++i) {
    if (!std::isfinite(ox[i]) || !std::isfinite(oy[i])) continue;
    Feature2 p;
    p.p = {double(ox[i]), double(oy[i])};
    p.kind = FeatureKind(okind[i]);
    p.group = ogroup[i];
    p.t = ot[i];
    res.points.push_back(p);
    res.source.push_back(osrc[i]);
  }
  return res;
}

}  // namespace fploc::feat::reference
