#include "fploc/eval/reference_noise.h"

#include <array>
#include <cmath>
#include <stdexcept>

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
  // Differences of the increments, accumulated for the three pairs: sums of squares and sums (for the mean).
  struct Acc {
    double s[3] = {0, 0, 0}, ss = 0, ssyaw = 0;  // x, y, yaw sums; sum of x^2 + y^2; sum of yaw^2
    void add(const Pose2& a, const Pose2& b) {
      const double dx = a.x - b.x, dy = a.y - b.y, dyaw = wrap_angle(a.yaw - b.yaw);
      s[0] += dx, s[1] += dy, s[2] += dyaw;
      ss += dx * dx + dy * dy;
      ssyaw += dyaw * dyaw;
    }
    double var_xy(size_t n) const { return (ss - (s[0] * s[0] + s[1] * s[1]) / double(n)) / double(n - 1); }
    double var_yaw(size_t n) const { return (ssyaw - s[2] * s[2] / double(n)) / double(n - 1); }
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
  const size_t n = r.increments;
  const auto xy = split(re.var_xy(n), rt.var_xy(n), et.var_xy(n));
  const auto yaw = split(re.var_yaw(n), rt.var_yaw(n), et.var_yaw(n));
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
