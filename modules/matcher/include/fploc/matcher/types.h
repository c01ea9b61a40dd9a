// Transport-free input/output types of the localization libraries (matcher, optimizer, odometry).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
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
  std::vector<Feature2> points;
};

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
