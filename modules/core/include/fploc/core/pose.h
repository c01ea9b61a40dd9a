// Poses and TUM trajectory files (`t x y z qx qy qz qw`, t in seconds), readable by evo.
#pragma once
#include <Eigen/Geometry>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace fploc {

struct Pose2 {
  double x = 0, y = 0, yaw = 0;
};

// Wraps an angle to (-pi, pi].
double wrap_angle(double a);

// SE(2): a (+) b (b expressed in a's frame, composed), the inverse, and a^-1 (+) b.
Pose2 compose(const Pose2& a, const Pose2& b);
Pose2 inverse(const Pose2& a);
inline Pose2 between(const Pose2& a, const Pose2& b) { return compose(inverse(a), b); }
// The pose a share f in [0, 1] of the way from a to b: a (+) f * (a^-1 (+) b) (the increment scaled
// linearly, e.g. odometry between two samples).
Pose2 interpolate(const Pose2& a, const Pose2& b, double f);

struct StampedPose {
  double t = 0;  // seconds
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();

  Eigen::Isometry3d iso() const;
  static StampedPose from(double t, const Eigen::Isometry3d& T);
  // roll/pitch/yaw (ZYX: R = Rz(yaw) Ry(pitch) Rx(roll)).
  static StampedPose from_rpy(double t, const Eigen::Vector3d& p, double roll, double pitch, double yaw);
  Eigen::Vector3d rpy() const;
};

using Trajectory = std::vector<StampedPose>;

// One TUM line with fixed formatting (identical input gives byte-identical output).
std::string tum_line(const StampedPose& p);
// Reads a TUM file; skips blank lines and '#' comments. Throws std::runtime_error("file:line: ...").
Trajectory read_tum(const std::string& path);
void write_tum(const std::string& path, const Trajectory& traj);

}  // namespace fploc
