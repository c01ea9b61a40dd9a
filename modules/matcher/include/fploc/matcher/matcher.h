// Single-frame registration (paper Section IV-C, first stage): (x, y, yaw) of one scan's projected
// features against the floor plan, with Ceres (single-threaded, deterministic).
#pragma once
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "fploc/matcher/lookup.h"
#include "fploc/matcher/types.h"

namespace fploc {

struct MatcherConfig {
  double gate_initial_m = 1.5;    // correspondence gate of the first outer iteration
  double gate_final_m = 0.3;      // ... halved each outer iteration down to this
  double gate_tracking_m = 0.6;   // first gate while tracking (previous frame OK)
  double loss_scale_m = 0.05;     // robust (Huber) loss scale
  std::string loss = "huber";     // "huber", "cauchy", "none"
  int max_iterations = 10;        // Ceres iterations per outer iteration
  int max_outer = 5;              // look-up + solve rounds (x6 for point targets, see matcher.cpp)
  double inlier_m = 0.1;          // a point within this of the plan is an inlier
  double min_inlier_ratio = 0.3;  // below: POOR (the pose is not accepted)
  int min_inliers = 15;
  int lost_after = 5;             // consecutive POOR frames -> LOST
  double max_jump_m = 1.5;        // an OK-looking fit this far from the prediction is refused
  double max_jump_rad = 0.5;
  bool group_rule = true;
  bool motion_model = true;       // constant velocity (else: previous pose)
  int stride = 1;                 // use every stride-th point
  int max_points = 800;           // more features than this: the stride grows to keep about this many (0 = all)
};

struct MatchResult {
  FitStatus status = FitStatus::kNotInitialised;
  std::string text;
  Pose2 pose;                     // accepted pose (the prediction when POOR/LOST)
  Pose2 solved;                   // what the solver found (equal to pose when OK)
  Pose2 predicted;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  FitQuality fit;
  int iterations = 0;
};

// Stateless registration from an initial guess (used by the Matcher and by tests).
MatchResult register_frame(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& guess,
                           const MatcherConfig& cfg);

class Matcher {
 public:
  Matcher(const NearestLookup& lookup, MatcherConfig cfg);
  // (Re)initialises the tracker: the next frame is registered from this pose (no motion model).
  void set_pose(const Pose2& p);
  bool initialised() const { return initialised_; }
  // Registers the frame. yaw_delta: the IMU's integrated yaw change since the previous frame, if any.
  MatchResult process(const FeatureFrame& f, std::optional<double> yaw_delta = std::nullopt);
  const MatcherConfig& config() const { return cfg_; }

 private:
  Pose2 predict(int64_t utime, std::optional<double> yaw_delta) const;
  const NearestLookup& lookup_;
  MatcherConfig cfg_;
  bool initialised_ = false;
  bool have_last_ = false;      // a registered frame exists (utime_ valid)
  bool have_velocity_ = false;
  Pose2 pose_;
  int64_t utime_ = 0;
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();  // vx, vy [m/s], yaw rate [rad/s] (plan frame)
  int poor_count_ = 0;
};

}  // namespace fploc
