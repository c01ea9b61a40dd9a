// The localization pipeline of the paper (Section IV-C) as one object, in the style of KISS-ICP's
// pipeline class: it owns the IMU yaw (prediction and sweep yaw rate), the attitude hold (roll/pitch/z
// the segmenter could not estimate are held at their last known values), the single-frame matcher (SFR)
// and the window optimizer (WO), configured by one Config. No transport: the matcher and optimizer nodes
// are thin adapters over it, one step each (the paper's SFR / WO split stays two processes in the
// graphs); in one process, process() runs both steps and feeds the window estimate back to the matcher,
// as graphs/paper.pbtxt wires FPLOC_POSE_LATEST into the matcher's `refined` input.
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fploc/floorplan/free_space.h"
#include "fploc/localizer/degeneracy.h"
#include "fploc/matcher/imu_yaw.h"
#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/odometry/odometry.h"
#include "fploc/optimizer/window.h"

namespace fploc::localizer {

struct Config {
  matcher::MatcherConfig matcher;             // the SFR step
  optimizer::OptimizerConfig optimizer;         // the WO step
  bool use_imu = true;               // the IMU's yaw rate: prediction (yaw change) + sweep yaw rate (de-skew)
  double initial_search_m = 0;       // set_pose without an uncertainty: search this far (0: matcher.max_correspondence_m)
  bool refine_from_window = true;    // process(): the WO estimate of a frame predicts the next one
  // add_odometry: a frame's odometry pose is the sample at its utime, else interpolated between the two around
  // it, else the newest one when no older than this (odometry at its own rate, e.g. a robot's 50 Hz).
  double odometry_max_age_s = 0.25;
  // The published covariance and status (degeneracy.h); its frame loss/gate follow `matcher` unless
  // set apart (Localizer's constructor copies them).
  UncertaintyConfig uncertainty;
  // The map's free space when the plan is an occupancy map (LocalizationMap::free_space; not owned: the caller
  // keeps it alive, as ActivePlan does): the published status checks each fix against it
  // (UncertaintyConfig::max_contradicted). Null: no such check.
  const FreeSpace* free_space = nullptr;
  // The plan's own position error shared by every point of a frame (LocalizationMap::map_sigma_m: an occupancy
  // map's cell): added to the published covariance, map_sigma_m in x and y and that over the frame's median
  // point range in yaw, as the grid localizer does. Published only: the tracker's gates and the window keep the
  // fit's own covariance (the map's error is the same on the next frame, not a random walk to accumulate).
  // Without it the plan path on the Radish logs' vectorised maps published covariances that its errors against
  // the reference exceeded by NEES 70-198 (3 when consistent). 0: none (drawn plans).
  double map_sigma_m = 0;
};

// What a Config takes from the map it runs on: its free space and its own position error (ActivePlan and the
// tools that build a Localizer on a LocalizationMap call this; the map must outlive the Localizer).
void use_map(Config& cfg, const matcher::LocalizationMap& map);

// The SFR step's result for one frame (what FPLOC_FRAME_POSE carries).
struct FramePose {
  int64_t utime = 0;
  int64_t scan_seq = 0;
  matcher::MatchResult match;
  // Roll/pitch/z of the frame, the last known ones where the frame's own are unknown (attitude hold),
  // and the frame's own sigmas (an "unknown" sigma tells the value is held).
  double roll = 0, pitch = 0, z = 0;
  double roll_pitch_sigma = kUnknownRollPitchSigmaRad, z_sigma = kUnknownZSigmaM;
  // The floor the frame was registered on (index in the building's floor list, its name); z is the
  // height above that floor's floor. A single plan is floor 0 named "0".
  int floor_index = 0;
  std::string floor = "0";
};

// A localized pose (the WO step's output): PoseOut carries its (x, y, yaw) covariance and its own z and
// roll/pitch sigmas.
using Pose = optimizer::PoseOut;

class Localizer {
 public:
  Localizer(const matcher::NearestLookup& lookup, Config cfg);

  // IMU gyro z sample (out-of-order or non-finite samples are ignored). Ignored unless cfg.use_imu.
  void add_imu(int64_t utime, double gyro_z);
  // The robot's own odometry pose at utime (e.g. wheel odometry of a 2D-LiDAR robot, at its own rate or at
  // the scans' times); when the poses at the previous and the current frame's utime are both known (a sample
  // there, or interpolated: odometry_max_age_s), their increment predicts the frame
  // (Matcher::process's `motion`), and the published uncertainty's track in optimize() (the tracker's
  // innovation gate, degeneracy.h). The last 256 are kept.
  void add_odometry(int64_t utime, const Pose2& p);
  // (Re)initialises the single-frame tracker at p, searching within search_m (default: cfg.initial_search_m).
  void set_pose(const Pose2& p, std::optional<double> search_m = std::nullopt);
  // A better estimate of the last registered frame's pose (the window's): see Matcher::refine.
  bool refine(int64_t utime, const Pose2& pose_at_utime) { return matcher_.refine(utime, pose_at_utime); }

  // SFR step: registers one frame (as measured) against the plan, with the IMU's prediction and the
  // attitude hold. Status kNotInitialised until set_pose.
  FramePose register_frame(const FeatureFrame& f);
  // WO step: the frame as measured and its SFR result (in time order). Frames not registered
  // (kNotInitialised) are skipped (nullopt). Otherwise appends the poses that became final to `finals`
  // and returns the current window estimate of this frame.
  std::optional<Pose> optimize(const FeatureFrame& f, const FramePose& sfr, std::vector<Pose>* finals);
  // A pose the matcher should be started again at (UncertaintyConfig::dr_reseed_when_lost), once, after the
  // optimize() that found it: the frame's utime, the pose there and the search radius for set_pose. process()
  // applies it itself; in the two-process graph the optimizer node sends it to the matcher node (FPLOC_RESEED).
  struct Reseed {
    int64_t utime = 0;
    Pose2 pose;
    double search_m = 0;
  };
  std::optional<Reseed> take_reseed() {
    auto r = reseed_;
    reseed_.reset();
    return r;
  }
  // Makes every pose still in the window final (end of a sequence).
  void flush(std::vector<Pose>* finals) { window_.flush(finals); }
  // A frame's z ends a dead-reckoned stretch before a flush (optimizer::WindowOptimizer::end_z_stretch).
  void end_z_stretch(const FeatureFrame& f) { window_.end_z_stretch(f); }

  // What follows the WO step in one process (process(), tools that time the steps apart): the matcher started again at
  // a re-seed (take_reseed) if there is one, else refined with the window's estimate of the frame (cfg.refine_from_window).
  void feed_back(const std::optional<Pose>& latest);
  // Both steps in one process.
  struct Step {
    FramePose sfr;
    std::optional<Pose> latest;
  };
  Step process(const FeatureFrame& f, std::vector<Pose>* finals);

  const Config& config() const { return cfg_; }
  const matcher::Matcher& matcher() const { return matcher_; }
  // The uncertainty published with the last optimize()d frame.
  const UncertaintyState& uncertainty() const { return uncertainty_; }
  // Of the frame's points at x that the map has an opinion about (inliers: inlier_ratio of them; and those in
  // cfg.free_space beyond the matcher's inlier distance), the share in free space (0 without a free space).
  // The published status checks each fix with it (UncertaintyConfig::max_contradicted).
  double contradicted(const FeatureFrame& f, const Pose2& x, double inlier_ratio) const;

 private:
  // The odometry pose at a frame's time (see Config::odometry_max_age_s), and the increment between two
  // frames' times in the first one's body frame.
  std::optional<Pose2> odometry_at(int64_t utime) const;
  std::optional<Pose2> odometry_between(int64_t from_utime, int64_t to_utime) const;
  // Adds cfg_.map_sigma_m's term (see Config) for frame f to a published covariance.
  void add_map_error(const FeatureFrame& f, Eigen::Matrix3d* covariance);
  Config cfg_;
  const matcher::NearestLookup& lookup_;
  matcher::Matcher matcher_;
  optimizer::WindowOptimizer window_;
  matcher::ImuYaw imu_;
  bool have_prev_ = false;           // a frame was registered (prev_utime_ valid)
  int64_t prev_utime_ = 0;
  std::optional<double> last_z_;
  std::optional<std::pair<double, double>> last_rp_;
  std::map<int64_t, Pose2> odom_;    // odometry poses by utime (add_odometry)
  bool have_prev_optimized_ = false;  // optimize() saw a frame (prev_optimized_utime_ valid)
  int64_t prev_optimized_utime_ = 0;
  FeatureFrame held_;                // scratch: the frame with the IMU's sweep rate and the held attitude
  FeatureFrame deskewed_;            // scratch: the frame de-skewed as the matcher registered it
  std::vector<double> ranges_;       // scratch: the frame's point ranges (add_map_error)
  UncertaintyTracker tracker_;
  UncertaintyState uncertainty_;
  // Dead reckoning (UncertaintyConfig::dead_reckoning_gate_sigma): the LiDAR odometry registers every frame; the
  // frames published OK outside a stretch are its anchors (their fixes carried on by the odometry's motion since).
  // Outside a stretch a fix is checked against the oldest anchor of the last dr_history_s (a track sliding a little
  // per frame drifts away from it), in a stretch against the anchor frozen at its start.
  std::optional<DeadReckoned> dead_reckoned(const FeatureFrame& f, const FramePose& sfr);
  struct Anchor {
    int64_t utime = 0;
    Pose2 fix;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
    Pose2 odometry;                                       // the odometry's pose at it
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();   // the fix's (the matcher's twist, plan frame)
    double path_m = 0, turn_rad = 0;                      // the odometry's path / turn at it (running totals)
    Eigen::Matrix2d open = Eigen::Matrix2d::Zero();       // x/y covariance carried along open directions since it
  };
  std::deque<Anchor> ok_frames_;     // oldest first
  bool reacquiring_without_dr_ = false;  // the dead reckoning was lost in a stretch that refused a fix: check_rival next
  bool have_frozen_ = false;         // the anchor of the current stretch
  Anchor frozen_;
  bool last_off_dead_reckoning_ = false;  // the previous frame failed the dead reckoning's gate (against the oldest anchor)
  std::optional<odometry::Odometry2D> dr_odometry_;
  Pose2 dr_last_;                    // the odometry's last pose
  double dr_path_m_ = 0, dr_turn_rad_ = 0;  // running totals
  int64_t dr_last_utime_ = 0;
  Eigen::Vector2d dr_velocity_ = Eigen::Vector2d::Zero();  // the odometry's over its last frame
  // UncertaintyConfig::dr_refit_ratio: the frame registered again from the dead-reckoned pose, when the fix lies beyond
  // the dead reckoning's gate; the fit (its pose at the frame's utime and at the de-skew reference) if it replaces the fix.
  struct Refit {
    matcher::MatchResult match;  // pose at utime, fit, covariance (the twist the fix's)
    Pose2 at_ref;
  };
  // (lost: the matcher is LOST, its pose is a stale prediction: the fix's gate test is skipped.)
  std::optional<Refit> refit_from_dead_reckoning(const FeatureFrame& deskewed, const FramePose& sfr, const Pose2& fix_at_ref,
                                                 const Eigen::Matrix3d& fix_covariance, const DeadReckoned& dr, double t_ref,
                                                 bool lost = false);
  std::optional<Reseed> reseed_;
  // The second fit of a re-acquisition (UncertaintyConfig::rival_ratio, rival_min_gained; rival.h): searched while
  // none is known during a confirmation (or the one carried is no ambiguity any more), then carried with the fix;
  // applied to uncertainty_. Also on the OK fixes after the dead reckoning was lost in a stretch that refused a fix
  // (reacquiring_without_dr_), there with a rival_ratio of at least 1. True: an ambiguity (published POOR, the
  // re-acquisition's confirmation started again).
  // (dr: the frame's dead-reckoned pose, if any: a rival beyond its gate is no ambiguity.)
  bool check_rival(const FeatureFrame& deskewed, const Pose2& fix_at_ref, const DeadReckoned* dr, const Pose2& fix_at_utime);
  bool have_rival_ = false;
  Pose2 rival_offset_;               // the rival in the fix's frame
};

}  // namespace fploc::localizer
