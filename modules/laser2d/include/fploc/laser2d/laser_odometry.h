// Laser odometry for the grid localizer: the motion between two scans measured by matching each scan to a
// local map of the scans just before it, as local SLAM front ends do (Cartographer's local trajectory
// builder, slam_toolbox's scan matcher): the robot's own recent scans explain where it moved even where the
// building map does not (rooms the map saw only through a door, furniture, a corridor drawn since).
//
// Per scan: the wheel odometry's increment (calibrated) predicts the pose in the local map's own frame (a
// frame of its own, which drifts slowly and is never corrected: only increments leave this class); the
// scan is refined on the distance field of the last map_scans scans at their local poses (Ceres, the
// field's residuals with a Huber loss, the wheel prediction as a prior with its step sigmas); the match is
// kept when at least min_inlier_ratio of the scan's points lie within inlier_m of the local map and the
// correction of the wheel step is within gate_sigmas of its sigma. A kept match gives the increment; a
// failed one gives none (the caller uses the wheels) and its scan joins the map at the wheel prediction.
// Transport-free.
#pragma once
#include <Eigen/Core>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "fploc/core/pose.h"

namespace fploc::laser2d {

struct LaserOdometryConfig {
  int map_scans = 10;            // the local map: the last map_scans scans
  double resolution_m = 0.05;    // its raster
  double field_max_m = 0.5;      // its distance field's truncation
  double inlier_m = 0.1;         // a point within this of a local map cell is explained by it
  double min_inlier_ratio = 0.5; // a match needs this share of the scan's points explained
  double gate_sigmas = 3.0;      // and a correction of the wheel step within this many of its sigmas
  double point_sigma_m = 0.05, huber_m = 0.05;
  int max_iterations = 20;
  double max_map_extent_m = 60;  // the local map's raster is capped at this size (around the current pose)
};

struct LaserOdometryStep {
  Pose2 increment;               // the motion since the previous scan (its frame)
  double inlier_ratio = 0;        // the share of the scan the local map explains
};

class LaserOdometry {
 public:
  explicit LaserOdometry(LaserOdometryConfig cfg = {});
  ~LaserOdometry();
  LaserOdometry(LaserOdometry&&) noexcept;
  LaserOdometry& operator=(LaserOdometry&&) noexcept;
  // points: the scan in the robot frame; wheel_inc: the wheels' increment since the previous scan with its
  // sigmas. Returns the matched increment, or nothing on the first scan and when the match fails.
  std::optional<LaserOdometryStep> update(const std::vector<Eigen::Vector2d>& points, const Pose2& wheel_inc,
                                          double sigma_xy_m, double sigma_yaw_rad);
  void reset();
  const LaserOdometryConfig& config() const { return cfg_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  LaserOdometryConfig cfg_;
};

}  // namespace fploc::laser2d
