#include "askew_faces.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace fploc::matcher {

void askew_points(const std::vector<TargetGeom>& g, const FeatureFrame& f, const Pose2& x, const std::vector<int>& on,
                  const AssignOptions& o, std::vector<char>* drop) {
  constexpr double kChi2Dof1P99 = 6.63;
  constexpr int kMinPoints = 4;         // fewer: never judged askew
  constexpr int kMinYawPoints = 10;     // runs that vote on the guess's yaw error
  constexpr size_t kSample = 40;        // points per run for the pairwise slopes
  constexpr double kMinBaseM = 0.05;    // pairs closer along the element give no slope
  constexpr double kInlierSigmas = 3;
  constexpr double kRunGapM = 0.5;
  struct Obs {
    int el, i;
    double s, r;  // along the element from its start, along its left normal [m]
  };
  thread_local std::vector<Obs> obs;
  obs.clear();
  for (size_t i = 0; i < on.size(); ++i) {
    if (on[i] < 0) continue;
    const TargetGeom& e = g[size_t(on[i])];
    if (e.kind != ElementKind::kSegment || !(e.len > 0)) continue;
    const Eigen::Vector2d pw = transform(x, f.points[i].p);
    const Eigen::Vector2d nrm(-e.u.y(), e.u.x());
    obs.push_back({on[i], int(i), (pw - e.a).dot(e.u), (pw - e.a).dot(nrm)});
  }
  std::sort(obs.begin(), obs.end(), [](const Obs& a, const Obs& b) { return a.el != b.el ? a.el < b.el : a.s < b.s; });
  const double ps2 = o.askew_point_sigma_m * o.askew_point_sigma_m;
  struct Run {
    size_t b, e;
    double slope, var, len;
    int n;
  };
  thread_local std::vector<Run> runs;
  thread_local std::vector<double> slopes;
  runs.clear();
  for (size_t b = 0; b < obs.size();) {
    size_t e = b + 1;
    while (e < obs.size() && obs[e].el == obs[b].el && obs[e].s - obs[e - 1].s <= kRunGapM) ++e;
    const size_t n = e - b;
    if (n >= size_t(kMinPoints)) {
      const size_t step = std::max<size_t>(1, n / kSample);
      slopes.clear();
      for (size_t k = b; k < e; k += step)
        for (size_t l = k + step; l < e; l += step) {
          const double ds = obs[l].s - obs[k].s;
          if (ds > kMinBaseM) slopes.push_back((obs[l].r - obs[k].r) / ds);
        }
      if (!slopes.empty()) {
        std::nth_element(slopes.begin(), slopes.begin() + long(slopes.size() / 2), slopes.end());
        const double m = slopes[slopes.size() / 2];
        slopes.clear();
        for (size_t k = b; k < e; ++k) slopes.push_back(obs[k].r - m * obs[k].s);
        std::nth_element(slopes.begin(), slopes.begin() + long(slopes.size() / 2), slopes.end());
        const double c0 = slopes[slopes.size() / 2], lim2 = kInlierSigmas * kInlierSigmas * ps2;
        // Least squares over the inliers: slope = S_sr / S_ss about their means, variance ps^2 / S_ss.
        double n_in = 0, ms = 0, mr = 0;
        for (size_t k = b; k < e; ++k) {
          const double ee = obs[k].r - (c0 + m * obs[k].s);
          if (ee * ee > lim2) continue;
          n_in += 1;
          ms += obs[k].s;
          mr += obs[k].r;
        }
        if (n_in >= kMinPoints) {
          ms /= n_in;
          mr /= n_in;
          double sss = 0, ssr = 0;
          for (size_t k = b; k < e; ++k) {
            const double ee = obs[k].r - (c0 + m * obs[k].s);
            if (ee * ee > lim2) continue;
            sss += (obs[k].s - ms) * (obs[k].s - ms);
            ssr += (obs[k].s - ms) * (obs[k].r - mr);
          }
          if (sss > 0) runs.push_back({b, e, ssr / sss, ps2 / sss, g[size_t(obs[b].el)].len, int(n_in)});
        }
      }
    }
    b = e;
  }
  // The guess's yaw error: the point-weighted median slope of the well-seen runs.
  thread_local std::vector<std::pair<double, int>> votes;
  votes.clear();
  int total = 0;
  for (const Run& r : runs)
    if (r.n >= kMinYawPoints) {
      votes.push_back({r.slope, r.n});
      total += r.n;
    }
  double yaw_err = 0;
  if (!votes.empty()) {
    std::sort(votes.begin(), votes.end());
    int acc_n = 0;
    for (const auto& v : votes) {
      acc_n += v.second;
      if (2 * acc_n >= total) {
        yaw_err = v.first;
        break;
      }
    }
  }
  drop->assign(on.size(), 0);
  const double P = o.askew_max_m;
  for (const Run& r : runs) {
    const double d = (r.slope - yaw_err) * r.len, var = r.var * r.len * r.len;
    if (d * d > kChi2Dof1P99 * (2 * P * P + var))
      for (size_t k = r.b; k < r.e; ++k) (*drop)[size_t(obs[k].i)] = 1;
  }
}

}  // namespace fploc::matcher
