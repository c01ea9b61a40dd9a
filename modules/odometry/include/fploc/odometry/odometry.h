// The no-floor-plan baseline: 2D LiDAR odometry on the same projected features the matcher uses.
// Frame-to-local-map ICP (point-to-line, Huber-weighted Gauss-Newton on (x, y, yaw)); the local map is
// the features of the last N keyframes placed with their odometry poses (like LOAM's local map), so
// errors accumulate: this is the drift the floor plan removes. Starts from the same initial pose as the
// matcher so its trajectory is in the plan frame.
#pragma once
#include <Eigen/Core>
#include <cmath>
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
  // Static points only (0: off, every map point with a line-like neighbourhood is registered against). A map point
  // is kept only where another keyframe of the map saw the same line: a point of another keyframe within the
  // normal neighbourhood (0.25 m) and within static_support_m of the point's local line. Walls, shelves and parked
  // things are seen again from the next keyframe (0.3 m of travel on); a walking person has moved by then (a
  // 0.45 m blob, seen again a body width or more away), so the trail of people a crowd leaves in the map does not
  // pull the registration along with them. Needs two keyframes: with one (the start) every point is kept.
  double static_support_m = 0;
  // The constant-velocity prediction as a prior of the registration (0: off), once the velocity is known: its 1-sigma
  // per frame, against point_sigma_m of a point's distance to its line. Where the points fix the pose (hundreds of
  // them on two walls) it moves the answer by nothing; along a direction they leave open (a corridor's axis) the
  // pose keeps the velocity instead of sliding wherever the few points off the walls (a passing person) pull it.
  double prediction_sigma_m = 0, prediction_sigma_rad = 0;
  double point_sigma_m = 0.03;
};

struct OdometryResult {
  Pose2 pose;
  bool ok = false;          // false: not enough correspondences (the prediction is kept)
  bool keyframe = false;
  int num_points = 0, num_inliers = 0;
  double rms_m = 0;
  int iterations = 0;
  // What the points fix of the pose (x, y, yaw): sum of J J^T / point_sigma_m^2 over the points within huber_m of
  // their lines at the last iteration (the prior left out); its inverse is the registration's covariance, large along
  // a direction the points leave open. Zero when not registered.
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
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
  // The velocity (plan frame, as set_pose's) the next frame is predicted with, e.g. a better-known one from a
  // localizer's fix; the pose and the map stay.
  const Eigen::Vector3d& velocity() const { return velocity_; }
  // The next frame's yaw change since the last one, measured (a gyro's integral), with its 1-sigma: the next
  // process() predicts the yaw with it (instead of the velocity's yaw rate) and holds the registration to it as a
  // prior of that sigma, whether or not a velocity is known. Used once. What the points cannot do alone: among
  // people walking beside the robot the ICP turns with them, a gyro does not.
  void set_yaw_change(double dyaw, double sigma_rad) {
    yaw_change_ = dyaw;
    yaw_change_sigma_ = sigma_rad;
    have_yaw_change_ = std::isfinite(dyaw) && sigma_rad > 0;
  }
  void set_velocity(const Eigen::Vector3d& velocity) {
    velocity_ = velocity;
    have_velocity_ = true;
  }
  size_t map_points() const;

 private:
  struct Map;
  void add_keyframe(const FeatureFrame& f, const Pose2& p);
  const FeatureFrame& subsampled(const FeatureFrame& f);
  OdometryConfig cfg_;
  std::unique_ptr<Map> map_;
  std::deque<std::vector<Eigen::Vector2d>> keyframes_;  // world points per keyframe
  bool have_pose_ = false, have_last_ = false, have_velocity_ = false;
  Pose2 pose_, last_key_;
  int64_t utime_ = 0;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  double yaw_change_ = 0, yaw_change_sigma_ = 0;
  bool have_yaw_change_ = false;
  FeatureFrame sub_;  // scratch: the subsampled frame
};

}  // namespace fploc::odometry