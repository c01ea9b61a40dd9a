// The no-floor-plan baseline: 2D LiDAR odometry on the same projected features the matcher uses.
// Frame-to-local-map ICP (point-to-line, Huber-weighted Gauss-Newton on (x, y, yaw)); the local map is
// the features of the last N keyframes placed with their odometry poses (like LOAM's local map), so
// errors accumulate: this is the drift the floor plan removes. Starts from the same initial pose as the
// matcher so its trajectory is in the plan frame.
#pragma once
#include <Eigen/Core>
#include <deque>
#include <memory>
#include <vector>

#include "fploc/matcher/types.h"

namespace fploc::odometry {

struct OdometryConfig {
  double max_correspondence_m = 0.5;
  double keyframe_distance_m = 0.3;
  double keyframe_angle_rad = 10.0 * M_PI / 180;
  int map_keyframes = 10;
  int max_iterations = 30;
  double huber_m = 0.05;
  int normal_neighbours = 6;
  double min_inlier_ratio = 0.3;
  int max_points = 800;  // per frame: every k-th feature so that about this many are used (0 = all)
};

struct OdometryResult {
  Pose2 pose;
  bool ok = false;          // false: not enough correspondences (the prediction is kept)
  bool keyframe = false;
  int num_points = 0, num_inliers = 0;
  double rms_m = 0;
  int iterations = 0;
};

class Odometry2D {
 public:
  explicit Odometry2D(OdometryConfig cfg = {});
  ~Odometry2D();
  void set_pose(const Pose2& p);  // restarts (the map is cleared)
  // ... moving with this velocity (plan frame: vx, vy [m/s], yaw rate [rad/s]) when the first frame after the one
  // that starts the map is predicted (a track taken over in motion: along a corridor the ICP leaves the axis where
  // the prediction put it, and a restart at rest would stall there).
  void set_pose(const Pose2& p, const Eigen::Vector3d& velocity);
  OdometryResult process(const FeatureFrame& f);
  size_t map_points() const;

 private:
  struct Map;
  void add_keyframe(const FeatureFrame& f, const Pose2& p);
  OdometryConfig cfg_;
  std::unique_ptr<Map> map_;
  std::deque<std::vector<Eigen::Vector2d>> keyframes_;  // world points per keyframe
  bool have_pose_ = false, have_last_ = false, have_velocity_ = false;
  Pose2 pose_, last_key_;
  int64_t utime_ = 0;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
};

}  // namespace fploc::odometry