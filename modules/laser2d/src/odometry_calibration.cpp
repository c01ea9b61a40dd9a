#include "fploc/laser2d/odometry_calibration.h"

#include <algorithm>
#include <cmath>

namespace fploc::laser2d {

bool OdometryCalibration::observe(const Pose2& o, const Pose2& f) {
  const double s = std::hypot(o.x, o.y), t = wrap_angle(o.yaw);
  const double S = std::hypot(f.x, f.y), T = wrap_angle(f.yaw);
  if (!std::isfinite(s + t + S + T) || s > cfg_.max_step_m || S > cfg_.max_step_m) return false;
  const double e = wrap_angle(T - t);
  if (std::abs(e - (b_ * s + k_ * t)) > cfg_.outlier_rad) return false;
  const double l = cfg_.memory_m > 0 ? std::exp(-s / cfg_.memory_m) : 1.0;
  ss_ = l * ss_ + s * s;
  st_ = l * st_ + s * t;
  tt_ = l * tt_ + t * t;
  se_ = l * se_ + s * e;
  te_ = l * te_ + t * e;
  sS_ = l * sS_ + s * S;
  ss2_ = l * ss2_ + s * s;
  ++pairs_;
  solve();
  return true;
}

void OdometryCalibration::solve() {
  const double a = ss_ + cfg_.prior_bias_m2, d = tt_ + cfg_.prior_turn_rad2, off = st_;
  const double det = a * d - off * off;
  if (det > 0) {
    b_ = std::clamp((d * se_ - off * te_) / det, -cfg_.max_bias_rad_per_m, cfg_.max_bias_rad_per_m);
    k_ = std::clamp((a * te_ - off * se_) / det, -cfg_.max_turn_scale, cfg_.max_turn_scale);
  }
  c_ = std::clamp((sS_ + cfg_.prior_scale_m2) / (ss2_ + cfg_.prior_scale_m2), 1 - cfg_.max_scale_error, 1 + cfg_.max_scale_error);
}

Pose2 OdometryCalibration::correct(const Pose2& o) const {
  const double s = std::hypot(o.x, o.y), t = wrap_angle(o.yaw);
  const double dyaw = b_ * s + k_ * t;
  const double h = 0.5 * dyaw, ch = std::cos(h), sh = std::sin(h);
  return {c_ * (ch * o.x - sh * o.y), c_ * (sh * o.x + ch * o.y), wrap_angle(o.yaw + dyaw)};
}

}  // namespace fploc::laser2d
