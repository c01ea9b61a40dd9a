// One scan's 2D wall features (paper Section IV-B): what the feature extractor produces and the
// localization stages (matcher, optimizer, odometry, AMCL, relocalizer) consume, the transport-free twin
// of messages/features_t.lcm. Points are gravity-aligned, sensor-centred, projected to the horizontal
// plane; the gravity part of the pose (roll, pitch, z) and its sigmas are passed through from the
// segmenter.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace fploc {

enum class FeatureKind : int8_t { kCorner = 0, kSurface = 1 };

struct Feature2 {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();  // sensor-centred horizontal frame [m]
  FeatureKind kind = FeatureKind::kSurface;
  int32_t group = -1;                           // PCA line group, -1 unclassified
  float t = 0.f;                                // measurement time - frame utime [s] (motion compensation)
};

// What the extractor could make of the scan (features_t.status).
enum class FeatureStatus : int8_t { kOk = 0, kFewFeatures = 1, kBadInput = 2 };

struct FeatureFrame {
  int64_t utime = 0;
  int64_t scan_seq = 0;
  FeatureStatus status = FeatureStatus::kOk;
  double roll = 0, pitch = 0, z = 0;
  double roll_pitch_sigma = 0, z_sigma = 0;
  double attitude_t = 0;  // roll/pitch/z hold at utime + this [s] (mid-sweep; the optimizer interpolates)
  // The IMU's mean yaw rate [rad/s] over the sweep (utime .. utime + the points' largest t); NaN = unknown.
  double sweep_yaw_rate = std::numeric_limits<double>::quiet_NaN();
  int32_t num_groups = 0;  // PCA line groups (ids 0 .. num_groups - 1)
  std::vector<Feature2> points;
  size_t size() const { return points.size(); }
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

}  // namespace fploc
