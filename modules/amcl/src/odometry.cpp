#include "fploc/amcl/odometry.h"

#include <cmath>
#include <sstream>

#include "fploc/amcl/amcl.h"

namespace fploc::amcl {

WheelOdometrySim::WheelOdometrySim(WheelOdometryConfig c) : c_(c), rng_(c.seed) {}

Pose2 WheelOdometrySim::update(const Pose2& truth) {
  if (!have_) {
    have_ = true;
    last_truth_ = truth;
    odom_ = start_;
    return odom_;
  }
  const Pose2 inc = between(last_truth_, truth);
  last_truth_ = truth;
  const double d = std::hypot(inc.x, inc.y);
  distance_ += d;
  const double deg = M_PI / 180.0;
  Pose2 noisy;
  noisy.x = inc.x * (1.0 + c_.scale_error) + rng_.gaussian(c_.trans_noise_m_per_sqrt_m * std::sqrt(d));
  noisy.y = inc.y * (1.0 + c_.scale_error) + rng_.gaussian(c_.trans_noise_m_per_sqrt_m * std::sqrt(d));
  noisy.yaw = inc.yaw + c_.yaw_drift_deg_per_m * deg * d + rng_.gaussian(c_.yaw_noise_deg_per_sqrt_m * deg * std::sqrt(d));
  odom_ = compose(odom_, noisy);
  return odom_;
}

bool OdometryGuard::correct(const Pose2& raw, Pose2* out, std::string* problem) {
  if (!finite(raw)) {
    if (problem) *problem = "non-finite odometry pose (ignored)";
    return false;
  }
  if (have_) {
    const Pose2 step = between(last_raw_, raw);
    const double d = std::hypot(step.x, step.y);
    if (d > c_.max_step_m || std::abs(step.yaw) > c_.max_step_rad) {
      // Re-anchor: the corrected pose stays where the last one was.
      fix_ = compose(compose(fix_, last_raw_), inverse(raw));
      ++jumps_;
      if (problem) {
        std::ostringstream s;
        s.precision(3);
        s << "odometry jump of " << d << " m / " << std::abs(step.yaw) * 180 / M_PI
          << " deg between consecutive poses (limit " << c_.max_step_m << " m / " << c_.max_step_rad * 180 / M_PI
          << " deg): treated as no motion";
        *problem = s.str();
      }
    }
  }
  have_ = true;
  last_raw_ = raw;
  *out = compose(fix_, raw);
  return true;
}

}  // namespace fploc::amcl
