// Single-frame registration (paper Section IV-C, first stage): (x, y, yaw) of one scan's projected
// features against the floor plan, with Ceres (single-threaded, deterministic).
#pragma once
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fploc/matcher/as_built.h"
#include "fploc/matcher/lookup.h"
#include "fploc/matcher/types.h"

namespace fploc::matcher {

struct MatcherConfig {
  double max_correspondence_m = 1.5;  // correspondence gate of the first outer iteration
  double min_correspondence_m = 0.3;  // ... halved each outer iteration down to this
  double gate_tracking_m = 0.3;   // first gate while tracking (previous frame OK): the motion model is good to
                                  // centimetres, and structures not in the plan running parallel to it a few
                                  // decimetres away (cabinets along a wall) stay out of the correspondences
  double loss_scale_m = 0.05;     // robust loss scale
  std::string loss = "cauchy";    // "cauchy" (redescending: clutter in front of walls is rejected), "huber", "none"
  int max_iterations = 10;        // Ceres iterations per outer iteration
  int max_rounds = 5;             // look-up + solve rounds (x6 for point targets, see matcher.cpp)
  double initial_search_yaw_rad = 10 * M_PI / 180;  // default yaw uncertainty of a pose given by set_pose
  double inlier_m = 0.1;          // a point within this of the plan is an inlier
  double min_inlier_ratio = 0.3;  // below: POOR (the pose is not accepted)
  int min_inliers = 15;
  int lost_after = 5;             // consecutive POOR frames -> LOST
  double max_jump_m = 1.5;        // an OK-looking fit this far from the prediction is refused
  double max_jump_rad = 30 * M_PI / 180;
  bool group_rule = true;
  bool motion_model = true;       // constant velocity (else: previous pose)
  // The motion model's speed is the platform's at most (as fploc-ndt's prediction): a velocity measured between two
  // fixes above it is scaled down to it (0 = no limit).
  double max_speed_mps = 2.0;
  bool deskew = true;             // motion compensation with the motion model's twist (IMU yaw rate if given)
  int stride = 1;                 // use every stride-th point
  int max_points = 800;           // more features than this: the stride grows to keep about this many (0 = all)
  // With a stride > 1: the points of a plan element holding at most this many of the frame's points are all
  // kept, weighted as a point budget's estimate of the sum over all points (AssignOptions::element_quota);
  // 0 = off.
  int element_quota = 0;
  // While tracking (the prediction a prior of the registration): the points of a run along a plan segment that
  // lies on a line askew to it are left out of the frame (AssignOptions::askew_max_m; judged once at the
  // prediction); 0 = off.
  double askew_max_m = 0;
  // While tracking, the prediction enters the registration as one more measurement: its uncertainty over
  // one frame (a platform's deviation from constant velocity in 0.1 s plus the velocity estimate's error;
  // grows with the time since the last frame), weighed against the floor-plan residuals by the last fit's
  // rms. Negligible where the plan constrains the pose (hundreds of points), it holds the directions the
  // plan leaves open (along a featureless wall) instead of letting them slide. 0 = no prior.
  double prediction_sigma_m = 0.01;
  double prediction_sigma_rad = 0.01;
  // refine(): after set_pose, refined poses are used from the first one this close to the matcher's own.
  double refine_gate_m = 0.3;
  double refine_gate_rad = 5 * M_PI / 180;
  // Per plan element weight of its floor-plan terms (matcher/element_weights.h: from the plan-change
  // detector); null = all 1. Not owned: the caller keeps it alive and may change it between frames.
  const std::vector<float>* element_weight = nullptr;
  // With the robot's odometry (process()'s `motion`; 2D laser logs: frames a metre and tens of degrees apart)
  // the fit must lie within odom_gate_sigmas of the prediction, with the odometry's 1-sigma over the step
  // odom_sigma_m + odom_sigma_per_m * step in x/y and odom_sigma_rad + odom_sigma_per_rad * turn +
  // odom_sigma_rad_per_m * step in yaw (the grid localizer's wheel model, measured against the Radish
  // references; laser2d GridLocalizerConfig::sigma_*), and these add up over POOR frames (dead reckoning). A
  // fit outside is refused (POOR: the pose is the prediction), as the grid localizer's fit must stay in its
  // search window; once the window exceeds twice the tracking gate the frame is registered from a grid of
  // starts over it (capped at odom_max_search_m / _rad), as after set_pose. max_jump_* do not apply then.
  // 0: off (max_jump_* only).
  double odom_gate_sigmas = 3.0;
  double odom_sigma_m = 0.05, odom_sigma_per_m = 0.3;
  double odom_sigma_rad = 2.0 * M_PI / 180, odom_sigma_per_rad = 0.3, odom_sigma_rad_per_m = 3.0 * M_PI / 180;
  double odom_max_search_m = 2.5, odom_max_search_rad = 45.0 * M_PI / 180;
  // ... and a fit more than 2 sigma from the prediction needs this share of its points within inlier_m of the
  // plan (nearer ones min_inlier_ratio), as the grid localizer's (50 % / 40 % near): a place the odometry does
  // not support must explain the scan well to be taken.
  double odom_far_inlier_ratio = 0.5;
  // ... and the window search's fits are ranked by their inliers times exp(-m^2 / 2 kappa^2) of their
  // Mahalanobis offset m from the prediction (the grid localizer's prior, SearchWindow::prior_kappa).
  double search_prior_kappa = 1.5;
  // The first frame's search from a pose known only to within search_m (set_pose: the user's initial pose, a
  // relocalizer's answer): of its OK fits that explain at least initial_search_band as many points as the best one,
  // the one nearest the given pose (Mahalanobis, the half-widths as 3 sigma) is taken. Of two places the scan fits
  // about as well the given pose is the evidence left; the most points alone took a pose 0.3-0.5 m along the corridor
  // (cabinet faces on a drawn wall) over the truth the corridor's mixed and renovated worlds started at. A weight on
  // the offset, as the window search's, pulled a start 1 m off onto a wrong fit near it. 0: off (the most points).
  double initial_search_band = 0.9;
  // A gap: a frame more than gap_s after the last one (scans lost on the way: a sensor or network dropout, a stalled
  // node) without the robot's odometry. The prediction carries the last body velocity over the gap, turned by the
  // IMU's yaw change when given (the velocity's own yaw rate otherwise), and is known only to within 3 sigma of
  // gap_sigma_mps * dt + gap_sigma_mps2 * dt^2 / 2 in x/y (capped at gap_max_search_m) and gap_sigma_rad +
  // gap_sigma_rad_per_s * dt in yaw with the IMU (gap_sigma_rad_per_s_no_imu * dt without; capped at
  // gap_max_search_rad). A window wider than twice the tracking gate is searched from a grid of starts, as the odometry
  // window (search_prior_kappa), and so are the POOR frames after it until one registers; a fit beyond 2 sigma must
  // explain odom_far_inlier_ratio of the scan. Beyond gap_max_s the prediction is the last position (a velocity that
  // old says nothing), turned by the IMU's yaw change. Before, a frame a second or more after the last was predicted
  // at the last pose (no velocity, no IMU yaw) and registered within the tracking gate: after a 3 s gap of the room
  // loop, 1.27 m off, then a wrong fit 24 cm off kept for 23 s. gap_s 0: off.
  double gap_s = 0.5;
  double gap_max_s = 10.0;
  double gap_sigma_mps = 0.05, gap_sigma_mps2 = 0.25;
  double gap_sigma_rad = 1.0 * M_PI / 180, gap_sigma_rad_per_s = 0.5 * M_PI / 180, gap_sigma_rad_per_s_no_imu = 0.2;
  double gap_max_search_m = 3.0, gap_max_search_rad = 45.0 * M_PI / 180;
  AsBuiltModel as_built;          // per-wall end offsets eliminated (as_built.h); off by default
};

// A Gaussian prior on the registered pose (the motion model's prediction), as residuals
// sqrt_info (x - pose) (yaw difference wrapped) beside the floor-plan terms.
struct PosePrior {
  Pose2 pose;
  Eigen::Vector3d sqrt_info = Eigen::Vector3d::Zero();  // per x, y, yaw, in the floor-plan terms' units
};

struct MatchResult {
  FitStatus status = FitStatus::kNotInitialised;
  std::string text;
  Pose2 pose;                     // accepted pose at the frame's utime (the prediction when POOR/LOST)
  Pose2 solved;                   // what the solver found, at utime (equal to pose when OK)
  Pose2 predicted;                // at utime
  Pose2 sweep_pose;               // the accepted pose at utime + t_ref (what the registration estimates)
  double t_ref = 0;               // reference time of the de-skewed sweep [s after utime]
  Twist2 twist;                   // body twist of the motion compensation and of utime <-> t_ref
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  FitQuality fit;
  int iterations = 0;
};

// Stateless registration from an initial guess (used by the Matcher and by tests). `f` is registered as
// given (motion compensation, if any, is the caller's: see deskew()).
MatchResult register_frame(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& guess,
                           const MatcherConfig& cfg, const PosePrior* prior = nullptr);

class Matcher {
 public:
  Matcher(const NearestLookup& lookup, MatcherConfig cfg);
  // (Re)initialises the tracker: the next frame is registered from this pose (no motion model), searching
  // within search_m / search_yaw of it (the pose's uncertainty; defaults max_correspondence_m and
  // initial_search_yaw_rad). An uncertainty larger than twice the tracking gate is searched from a grid
  // of starts.
  void set_pose(const Pose2& p, std::optional<double> search_m = std::nullopt, std::optional<double> search_yaw = std::nullopt);
  bool initialised() const { return initialised_; }
  // Registers the frame; the result is the pose at f.utime. yaw_delta: the IMU's integrated yaw change
  // since the previous frame, if any (prediction). Motion compensation (cfg.deskew): the sweep is
  // de-skewed to its mean point time t_ref with the motion model's body twist (its yaw rate replaced by
  // f.sweep_yaw_rate when that is known) and registered there; the twist is then updated from the last
  // two registered sweep poses and carries the pose back from utime + t_ref to utime.
  // motion: the robot's own odometry increment since the previous frame (wheel odometry, in the previous
  // frame's body frame), if any: the prediction is the previous pose composed with it, whatever the time
  // between frames (2D laser logs have frames seconds and a metre apart), and the first gate is the wide
  // one (max_correspondence_m), as odometry over such a step is good to decimetres, not to the tracking gate.
  MatchResult process(const FeatureFrame& f, std::optional<double> yaw_delta = std::nullopt,
                      const std::optional<Pose2>& motion = std::nullopt);
  // A better estimate of the last processed frame's pose at its utime (the windowed optimizer's, which
  // holds directions a single frame leaves open, e.g. along a long wall): the next frame is predicted
  // from it (with the matcher's own velocity). Ignored (false) unless `utime` is the last processed
  // frame's, the tracker is initialised and not LOST (then the relocalizer, not the optimizer, re-seeds
  // it) and the pose is finite; after set_pose also until a refined pose agrees with the matcher's own
  // within refine_gate_m / refine_gate_rad (before, the optimizer's window may still be on the old track).
  bool refine(int64_t utime, const Pose2& pose_at_utime);
  // The body twist the motion model currently assumes (zero until two frames were registered).
  Twist2 twist() const { return twist_; }
  const MatcherConfig& config() const { return cfg_; }

 private:
  Pose2 predict(int64_t tau, std::optional<double> yaw_delta, const std::optional<Pose2>& motion = std::nullopt) const;
  // dt seconds since the last frame are a gap (MatcherConfig::gap_s).
  bool gap(double dt) const { return cfg_.gap_s > 0 && dt > cfg_.gap_s; }
  const NearestLookup& lookup_;
  MatcherConfig cfg_;
  bool initialised_ = false;
  bool have_last_ = false;      // a frame was processed since set_pose (tau_ valid)
  bool have_velocity_ = false;
  Pose2 pose_;                  // last accepted pose at tau_ (the sweep's reference time)
  int64_t tau_ = 0;
  int64_t last_utime_ = 0;      // utime of the last processed frame
  Pose2 utime_to_tau_;          // that frame's pose at utime -> its pose at tau_
  bool refine_armed_ = false;   // a refined pose agreed with the matcher's since set_pose
  Twist2 twist_;                // constant body twist between the last two registered sweep poses
  int poor_count_ = 0;
  double last_rms_ = 0;         // fit rms of the last OK frame
  double search_m_ = 0;         // uncertainty of the pose given by set_pose
  double search_yaw_ = 0;
  double dead_reckoned_m_ = 0;  // odometry mode: 1-sigma x/y / yaw accumulated over the POOR frames since the last OK
  double dead_reckoned_rad_ = 0;
  double gap_window_m_ = 0;     // a gap's search window (MatcherConfig::gap_s), kept over the POOR frames after it
  double gap_window_rad_ = 0;
  double gap_dt_s_ = 0;         // that gap's length
  FeatureFrame deskewed_;       // scratch
  // Registration from a grid of starts over +-s / +-a around `centre` (spacing 2/3 of it, the centre first):
  // the fit with the most inliers (then the lower rms), OK ones first; with `window` only fits within it,
  // their inliers weighted by the prior on the offset (search_prior_kappa); with `nearest_band` (and no window) the
  // nearest of the OK fits with at least that share of the best one's points.
  MatchResult search_grid(const FeatureFrame& in, const Pose2& centre, double s, double a, const MatcherConfig& cfg,
                          const Eigen::Vector2d* window = nullptr, double nearest_band = 0) const;
};

}  // namespace fploc::matcher