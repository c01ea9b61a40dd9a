// Transport-free input/output types of the localization libraries (matcher, optimizer, odometry); their
// input, the FeatureFrame, is core's (fploc/core/feature_frame.h).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "fploc/core/feature_frame.h"
#include "fploc/core/pose.h"

namespace fploc::matcher {

// Planar velocity of the sensor, in its own frame: linear [m/s] (x forward, y left) and yaw rate [rad/s].
// Constant over a sweep it is the motion model of the motion compensation (de-skewing).
struct Twist2 {
  double vx = 0, vy = 0, w = 0;
};

// Relative pose after moving with the constant body twist v for t seconds (SE(2) exponential).
Pose2 exp_twist(const Twist2& v, double t);
// The constant body twist that takes pose a to pose b in dt seconds (SE(2) logarithm / dt).
Twist2 log_twist(const Pose2& a, const Pose2& b, double dt);

// Motion compensation: every point, measured at f.utime + p.t from the moving sensor, expressed in the
// sensor frame at f.utime + t_ref, assuming the body twist v over the sweep:
// p' = exp_twist(v, p.t - t_ref) (+) p. A pose registered from the result is the pose at f.utime + t_ref.
// With t_ref = mean_time(f) an error of v distorts the sweep symmetrically about its middle instead of
// shifting it, so the registered pose hardly depends on v (a velocity estimated from registered poses
// and fed back into their de-skewing is a loop that oscillates when t_ref = 0).
void deskew(const FeatureFrame& raw, const Twist2& v, double t_ref, FeatureFrame* out);
// Largest |t| of the frame's points [s] (0 when the points carry no times).
double sweep_duration(const FeatureFrame& f);
// Mean t of the frame's points [s].
double mean_time(const FeatureFrame& f);

enum class FitStatus : int8_t { kOk = 0, kPoor = 1, kLost = 2, kNotInitialised = 3 };
const char* to_string(FitStatus s);

struct FitQuality {
  int num_points = 0;
  int num_inliers = 0;
  double inlier_ratio = 0;   // 0..1
  double rms_m = 0;          // over inliers
};

// Plan-frame transform of a sensor-frame point.
inline Eigen::Vector2d transform(const Pose2& x, const Eigen::Vector2d& p) {
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  return {c * p.x() - s * p.y() + x.x, s * p.x() + c * p.y() + x.y};
}

}  // namespace fploc::matcher