#include "fploc/eval/reference_noise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "fploc/eval/eval.h"

namespace fploc::eval {

namespace {

Pose2 planar(const StampedPose& p) { return {p.p.x(), p.p.y(), p.rpy().z()}; }

// For each reference index, the index of the associated pose of `other` (-1: none).
std::vector<long> partner_of_ref(const Trajectory& ref, const Trajectory& other, double max_dt, double offset) {
  std::vector<long> out(ref.size(), -1);
  for (const auto& [g, e] : associate(ref, other, max_dt, offset)) out[g] = long(e);
  return out;
}

// Three-cornered hat: the variances of A, B, C from those of A-B, A-C, B-C.
std::array<double, 3> split(double ab, double ac, double bc) {
  return {(ab + ac - bc) / 2, (ab + bc - ac) / 2, (ac + bc - ab) / 2};
}

}  // namespace

double signed_sqrt(double v) { return std::copysign(std::sqrt(std::fabs(v)), v); }

HatResult three_cornered_hat(const Trajectory& ref, const Trajectory& est, const Trajectory& third, double max_dt,
                             int lag, double est_offset) {
  if (lag < 1) throw std::invalid_argument("three-cornered hat: lag must be >= 1");
  const auto pe = partner_of_ref(ref, est, max_dt, est_offset), pt = partner_of_ref(ref, third, max_dt, 0);
  // Differences of the increments for the three pairs, kept: the variances are taken about the mean (two passes).
  // The one-pass sum-of-squares formula left a rounding residue of either sign where a difference is constant (a
  // stationary third trajectory against a straight constant-speed reference: 0 in exact arithmetic), printed as a
  // "negative variance" (-1.7e-9 m).
  struct Acc {
    std::vector<std::array<double, 3>> d;  // x, y, yaw
    void add(const Pose2& a, const Pose2& b) { d.push_back({a.x - b.x, a.y - b.y, wrap_angle(a.yaw - b.yaw)}); }
    // The variance of components [k0, k1] summed, about their means; *ms: their mean square (the scale the sums'
    // rounding is relative to).
    double var(int k0, int k1, double* ms) const {
      const double n = double(d.size());
      double v = 0, q = 0;
      for (int k = k0; k <= k1; ++k) {
        double mean = 0;
        for (const auto& x : d) mean += x[size_t(k)];
        mean /= n;
        for (const auto& x : d) v += (x[size_t(k)] - mean) * (x[size_t(k)] - mean), q += x[size_t(k)] * x[size_t(k)];
      }
      *ms = q / n;
      return v / (n - 1);
    }
  } re, rt, et;
  HatResult r;
  for (size_t i = 0; i + size_t(lag) < ref.size(); ++i) {
    const size_t j = i + size_t(lag);
    if (pe[i] < 0 || pe[j] < 0 || pt[i] < 0 || pt[j] < 0) continue;
    const Pose2 dr = between(planar(ref[i]), planar(ref[j]));
    const Pose2 de = between(planar(est[size_t(pe[i])]), planar(est[size_t(pe[j])]));
    const Pose2 dt = between(planar(third[size_t(pt[i])]), planar(third[size_t(pt[j])]));
    re.add(dr, de);
    rt.add(dr, dt);
    et.add(de, dt);
    ++r.increments;
  }
  if (r.increments < 3)
    throw std::invalid_argument("three-cornered hat: " + std::to_string(r.increments) +
                                " increments with all three trajectories (need >= 3; check the time stamps)");
  // The hat's estimates, an estimate within the sums' rounding (1e-12 of the largest mean square of the differences)
  // being 0: no noise measurable, neither positive nor negative. A pair's variance that overflowed (inf, NaN) leaves
  // none of the three separable: all NaN.
  auto hat = [&](int k0, int k1) {
    double m[3];
    const double ab = re.var(k0, k1, &m[0]), ac = rt.var(k0, k1, &m[1]), bc = et.var(k0, k1, &m[2]);
    if (!std::isfinite(ab) || !std::isfinite(ac) || !std::isfinite(bc) || !std::isfinite(m[0] + m[1] + m[2]))
      return std::array<double, 3>{NAN, NAN, NAN};
    auto v = split(ab, ac, bc);
    const double tiny = 1e-12 * std::max({m[0], m[1], m[2]});
    for (double& x : v)
      if (std::abs(x) <= tiny) x = 0;
    return v;
  };
  const auto xy = hat(0, 1);
  const auto yaw = hat(2, 2);
  HatSource* src[3] = {&r.ref, &r.est, &r.third};
  for (int k = 0; k < 3; ++k) {
    src[k]->increment_var_xy_m2 = xy[size_t(k)];
    src[k]->increment_var_yaw_rad2 = yaw[size_t(k)];
    src[k]->pose_sigma_xy_m = signed_sqrt(xy[size_t(k)] / 2);
    src[k]->pose_sigma_yaw_rad = signed_sqrt(yaw[size_t(k)] / 2);
  }
  return r;
}

}  // namespace fploc::eval
