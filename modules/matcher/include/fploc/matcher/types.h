// Transport-free input/output types of the localization libraries (matcher, optimizer, odometry).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "fploc/core/pose.h"

namespace fploc {

enum class FeatureKind : int8_t { kCorner = 0, kSurface = 1 };

struct Feature2 {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();  // sensor-centred horizontal frame [m]
  FeatureKind kind = FeatureKind::kSurface;
  int32_t group = -1;                           // PCA line group, -1 unclassified
  float t = 0.f;                                // measurement time - frame utime [s] (motion compensation)
};

// One scan's projected features plus the gravity part of the pose passed through from the segmenter.
struct FeatureFrame {
  int64_t utime = 0;
  int64_t scan_seq = 0;
  double roll = 0, pitch = 0, z = 0;
  double roll_pitch_sigma = 0, z_sigma = 0;
  double attitude_t = 0;  // roll/pitch/z hold at utime + this [s] (mid-sweep; the optimizer interpolates)
  // The IMU's mean yaw rate [rad/s] over the sweep (utime .. utime + the points' largest t); NaN = unknown.
  double sweep_yaw_rate = std::numeric_limits<double>::quiet_NaN();
  std::vector<Feature2> points;
};

// "Unknown" roll/pitch or height: the segmenter sends these sigmas for what it could not estimate; any
// sigma at or above the *_from threshold (or a non-finite value) means unknown.
inline constexpr double kUnknownZSigmaM = 1e3;
inline constexpr double kUnknownRollPitchSigmaRad = M_PI;
inline constexpr double kZUnknownFromSigmaM = 1.0;
inline constexpr double kRollPitchUnknownFromSigmaRad = 0.5;
inline bool z_known(const FeatureFrame& f) { return std::isfinite(f.z) && f.z_sigma < kZUnknownFromSigmaM; }
inline bool roll_pitch_known(const FeatureFrame& f) {
  return std::isfinite(f.roll) && std::isfinite(f.pitch) && f.roll_pitch_sigma < kRollPitchUnknownFromSigmaRad;
}

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

}  // namespace fploc
