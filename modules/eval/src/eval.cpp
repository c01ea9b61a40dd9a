#include "fploc/eval/eval.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace fploc::eval {

Align parse_align(const std::string& s) {
  if (s == "none") return Align::None;
  if (s == "se2") return Align::SE2;
  if (s == "se3") return Align::SE3;
  throw std::invalid_argument("alignment '" + s + "': expected none, se2 or se3");
}

Pairs associate(const Trajectory& gt, const Trajectory& est, double max_dt, double offset) {
  // Candidates within max_dt (gt sorted by time for the search), then greedy by |dt| like associate.py.
  std::vector<size_t> order(gt.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return gt[a].t < gt[b].t; });
  struct Cand {
    double d;
    size_t g, e;
  };
  std::vector<Cand> cands;
  for (size_t e = 0; e < est.size(); ++e) {
    const double t = est[e].t + offset;
    auto it = std::lower_bound(order.begin(), order.end(), t - max_dt,
                               [&](size_t g, double v) { return gt[g].t < v; });
    for (; it != order.end() && gt[*it].t <= t + max_dt; ++it) cands.push_back({std::abs(gt[*it].t - t), *it, e});
  }
  std::stable_sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) {
    if (a.d != b.d) return a.d < b.d;
    if (a.e != b.e) return a.e < b.e;
    return a.g < b.g;
  });
  std::vector<char> gu(gt.size(), 0), eu(est.size(), 0);
  Pairs out;
  for (const auto& c : cands) {
    if (gu[c.g] || eu[c.e]) continue;
    gu[c.g] = eu[c.e] = 1;
    out.emplace_back(c.g, c.e);
  }
  std::sort(out.begin(), out.end(), [&](const auto& a, const auto& b) {
    return est[a.second].t != est[b.second].t ? est[a.second].t < est[b.second].t : a.second < b.second;
  });
  return out;
}

Stats summarize(std::vector<double> v) {
  Stats s;
  s.n = v.size();
  if (v.empty()) return s;
  double sum = 0, sq = 0;
  for (double x : v) {
    sum += x;
    sq += x * x;
  }
  s.mean = sum / double(v.size());
  s.rmse = std::sqrt(sq / double(v.size()));
  s.stddev = std::sqrt(std::max(0.0, sq / double(v.size()) - s.mean * s.mean));
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  const size_t n = v.size();
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  return s;
}

Eigen::Isometry3d align(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, Align mode) {
  Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
  const long n = long(pairs.size());
  if (mode == Align::None) return S;
  if (mode == Align::SE3) {
    if (n < 3) return S;
    Eigen::Matrix3Xd src(3, n), dst(3, n);
    for (long k = 0; k < n; ++k) {
      src.col(k) = est[pairs[size_t(k)].second].p;
      dst.col(k) = gt[pairs[size_t(k)].first].p;
    }
    S.matrix() = Eigen::umeyama(src, dst, false);
    return S;
  }
  // SE(2): rotation about z and x-y translation (heights are compared as they are).
  if (n < 2) return S;
  Eigen::Matrix2Xd src(2, n), dst(2, n);
  for (long k = 0; k < n; ++k) {
    src.col(k) = est[pairs[size_t(k)].second].p.head<2>();
    dst.col(k) = gt[pairs[size_t(k)].first].p.head<2>();
  }
  const Eigen::Matrix3d T2 = Eigen::umeyama(src, dst, false);
  S.linear().topLeftCorner<2, 2>() = T2.topLeftCorner<2, 2>();
  S.translation().head<2>() = T2.topRightCorner<2, 1>();
  return S;
}

Ate ate(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, Align mode) {
  Ate r;
  r.S = align(gt, est, pairs, mode);
  r.errors.reserve(pairs.size());
  std::vector<double> xy;
  xy.reserve(pairs.size());
  for (const auto& [g, e] : pairs) {
    const Eigen::Vector3d d = gt[g].p - r.S * est[e].p;
    r.errors.push_back(d.norm());
    xy.push_back(d.head<2>().norm());
  }
  r.trans = summarize(r.errors);
  r.trans_xy = summarize(xy);
  return r;
}

Rpe rpe(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, double delta, bool frames,
        double max_gap_s) {
  std::vector<double> et, er;
  const size_t n = pairs.size();
  std::vector<double> times(n);
  for (size_t k = 0; k < n; ++k) times[k] = gt[pairs[k].first].t;
  for (size_t k = 0; k < n; ++k) {
    size_t m;
    if (frames) {
      m = k + size_t(std::max(1.0, std::round(delta)));
      if (m >= n) break;
    } else {
      const double want = times[k] + delta;
      auto it = std::lower_bound(times.begin(), times.end(), want);
      if (it == times.end()) {
        m = n - 1;
      } else {
        m = size_t(it - times.begin());
        if (m > 0 && std::abs(times[m - 1] - want) <= std::abs(times[m] - want)) --m;
      }
      if (m <= k || std::abs(times[m] - want) > max_gap_s) continue;
    }
    const Eigen::Isometry3d dq = gt[pairs[k].first].iso().inverse() * gt[pairs[m].first].iso();
    const Eigen::Isometry3d dp = est[pairs[k].second].iso().inverse() * est[pairs[m].second].iso();
    const Eigen::Isometry3d E = dq.inverse() * dp;
    et.push_back(E.translation().norm());
    // Rotation angle, well conditioned near 0 (acos of the trace is not).
    const Eigen::Matrix3d R = E.linear();
    const Eigen::Vector3d w(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
    er.push_back(std::atan2(0.5 * w.norm(), 0.5 * (R.trace() - 1.0)) * 180.0 / M_PI);
  }
  return {summarize(et), summarize(er)};
}

}  // namespace fploc::eval
