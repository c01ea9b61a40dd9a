// The 2D mode's scan-to-map localizer on a raster map (DistanceField of an occupancy grid), with the wheel
// odometry as the motion prior. Per scan:
//  1. prediction: the previous estimate composed with the odometry increment between the two scans (no
//     odometry: the previous estimate), and its uncertainty: sigma_xy = base + k_xy * step, sigma_yaw =
//     base + k_yaw * turn (+ k_yaw_per_m * step), added to what is left of the previous one; where the scan
//     matches the last few scans (laser_odometry.h) their increment replaces the odometry's, with its own sigmas;
//  2. a correlative search (Olson's correlative scan matching, as Cartographer's real-time matcher does it)
//     over a window of +-3 sigma around the prediction: every yaw step rotates the points once, every cell
//     offset sums the points' scores exp(-d^2 / 2 s^2) (d from the distance field); the score is weighted by a
//     weak Gaussian of the offset (ties along corridors go to the odometry);
//  3. refinement from the best candidate with Ceres: one residual per point, the distance field at the point
//     (bicubic interpolation) with a Huber loss, plus the prediction as a prior with the sigmas of step 1;
//  4. status: OK when the share of points within inlier_m of an occupied cell is at least min_inlier_ratio
//     (min_inlier_ratio_near when the fit is within gate_sigmas of the prediction);
//     else POOR and the estimate is the prediction, whose uncertainty keeps growing with the odometry, so the
//     next search window widens (recovery after a stretch the map does not explain); LOST after lost_after
//     POOR scans in a row, until a scan matches again.
// The first scan is searched over the initial pose's uncertainty (initial_sigma_*), e.g. a start 1 m / 10 deg
// off; without a start pose (start_global) the whole map is searched and several places tracked until one
// dominates (global_*). Transport-free: nodes/grid2d wraps it.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/floorplan/distance_field.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/laser2d/laser_odometry.h"
#include "fploc/laser2d/odometry_calibration.h"

namespace fploc::laser2d {

// The robust loss of the Ceres refinement's point residuals (scale huber_m): Huber's influence stays constant
// beyond the scale, Cauchy's and Tukey's fall off (points on structure the map lacks pull less).
enum class FitLoss { kHuber, kCauchy, kTukey };
// "huber", "cauchy", "tukey" (the names of graph options and tools); nullopt for any other.
std::optional<FitLoss> fit_loss_from_name(const std::string& name);

struct GridLocalizerConfig {
  // Odometry (prediction) uncertainty per scan step: sigma = base + k * |increment|.
  double sigma_xy_m = 0.05, sigma_xy_per_m = 0.3;
  double sigma_yaw_rad = 2.0 * M_PI / 180, sigma_yaw_per_rad = 0.3, sigma_yaw_per_m = 3.0 * M_PI / 180;
  // No odometry: the prediction is the previous pose with this uncertainty per scan.
  double no_odom_sigma_xy_m = 0.3, no_odom_sigma_yaw_rad = 10.0 * M_PI / 180;
  // Initial pose uncertainty (the first search window is +-3 sigma).
  double initial_sigma_xy_m = 0.5, initial_sigma_yaw_rad = 5.0 * M_PI / 180;
  // Search window: +-window_sigmas sigma, capped.
  double window_sigmas = 3.0, max_window_xy_m = 2.5, max_window_yaw_rad = 45.0 * M_PI / 180;
  double search_yaw_step_rad = 1.0 * M_PI / 180;
  double score_sigma_m = 0.1;       // correlative score exp(-d^2 / 2 s^2)
  // The search's prior: exp(-m^2 / (2 * this^2)), m = Mahalanobis. 1.5 (was 3): a sweep of 1, 1.5, 3 on all five
  // Radish logs (there is no held-out log): covered ATE intel 37.5 -> 18.1 cm, freiburg-079 336 -> 273, csail 9.8 -> 7.4,
  // fhw 5.7 -> 5.7, aces 8.3 -> 8.7 (ties along corridors go to the odometry more firmly).
  double prior_weight_sigmas = 1.5;
  // The search keeps the refine_candidates best distinct candidates (>= candidate_ratio of the best score) and
  // refines each; the least-cost refinement is the fit. 1 (default): the best only. 4 was tried on the Radish
  // logs (covered ATE intel 18.1 -> 23.9 cm, aces 8.7 -> 10.1, fhw 5.7 -> 11.0, freiburg-079 273 -> 213): the
  // least robust cost ignores the odometry's preference, so a better-fitting aliased candidate wins.
  // search_levels: pyramid levels of the branch-and-bound search (2^(levels-1) cells at the top).
  int refine_candidates = 1;
  // Odometry-consistent choice (issue 13, fifth pass): besides the search's best, the fit refined from the
  // prediction itself and up to consistent_candidates distinct search candidates are refined; the fit nearest
  // the prediction (Mahalanobis) is kept unless another has at least jump_inlier_margin more inlier share
  // (the map must clearly prefer a pose the odometry does not predict: in-place turns where a rotated fit
  // matches a partly mapped room as well as the true one, corridors where a shifted fit matches as well).
  // 0 candidates: off (the search's best only, the earlier behaviour).
  int consistent_candidates = 4;
  double jump_inlier_margin = 0.05;
  // ... applied only when the nearest fit and the search's best are different places (farther apart than
  // either); at the same place the search's best is kept (the odometry's own bias is not a conflict).
  double same_place_xy_m = 0.1, same_place_yaw_rad = 3.0 * M_PI / 180;
  // Among those candidates also the prediction refined in x, y only (the odometry's yaw kept): where the map
  // constrains the yaw weakly (a partly mapped room during an in-place turn) the refinement otherwise rotates
  // the scan 10-20 deg from an odometry turn that was right to a few degrees (intel scans 835-837).
  bool odometry_yaw_candidate = true;
  // While re-acquiring, a fit inside the searched window that explains at least this share of the scan ends
  // it at once even outside gate_sigmas (a large odometry turn error right after the map was lost: csail).
  double reacquire_strong_ratio = 0.9;
  // A failed tracking fit is retried once with the window widened by this factor (an odometry turn error
  // beyond the window: csail); the retry is taken only with min_inlier_ratio. 1: off.
  double retry_window_factor = 2.0;
  // Dead reckoning (POOR scans): the uncertainty grows with the motion only (sigma_*_per_*); the per-scan
  // bases (sigma_xy_m, sigma_yaw_rad) size the search window after a fit but are not added again on every
  // unmatched scan (a robot at 40 Hz that stands still for 150 scans is not 0.6 m / 25 deg less certain).
  bool dead_reckoning_motion_only = false;
  double candidate_ratio = 0.8;
  int search_levels = 8;
  // Refinement.
  double huber_m = 0.05;
  FitLoss fit_loss = FitLoss::kHuber;
  // With a redescending fit_loss: a refinement whose prediction is less certain than this (sigma x/y) runs Huber
  // first (field_fit.h, huber_first). <= 0: never.
  double huber_first_above_sigma_m = 0;
  double point_sigma_m = 0.05;
  int max_iterations = 20;
  // Points: returns within [min_range_m, max_range_m]; at most max_points (every k-th).
  double min_range_m = 0.1, max_range_m = 40.0;
  int max_points = 400;
  // Status.
  double inlier_m = 0.1;
  // A fit is accepted when at least min_inlier_ratio of the points are inliers, or min_inlier_ratio_near
  // when it also lies within gate_sigmas of the prediction (Mahalanobis, x y yaw): a fit that agrees with
  // the odometry needs less support from the map than a jump does (rooms the map saw only through a door).
  double min_inlier_ratio = 0.5;
  double min_inlier_ratio_near = 0.4;
  double gate_sigmas = 2.0;
  int lost_after = 10;
  // Re-acquisition while LOST (multiple hypotheses): a wide search (+-window_sigmas sigma of the dead-reckoned
  // prediction, capped at reacquire_xy_m / reacquire_yaw_rad) proposes up to reacquire_candidates distinct
  // poses per scan; each that fits (>= min_inlier_ratio) becomes a hypothesis tracked by the odometry and its own
  // local fit, dropped at its first failed fit; at most max_hypotheses. One is taken when it has matched
  // confirm_scans scans in a row and the runner-up has matched fewer than confirm_scans - 1 or has a mean
  // inlier share lower by confirm_margin. Off: a single accepted fit ends LOST (the earlier behaviour).
  bool reacquire = true;
  double reacquire_xy_m = 10.0, reacquire_yaw_rad = M_PI;
  bool follow_weak = true;   // while re-acquiring, follow a weak fit near the prediction (else dead-reckon)
  // ... also once LOST (lost_after POOR scans): off — after a long stretch the map does not explain, a weak fit
  // within the grown gate is as likely a wrong place (intel scan 799: 1.5 m off with 41 % inliers).
  bool follow_weak_when_lost = true;
  // Re-acquisition must not be a lottery (issue 13, seventh pass: intel's covered ATE was 155 or 9.9 cm depending
  // on a 5 mm difference in the start pose). Two rules while re-acquiring (POOR or LOST):
  // (1) a weak fit (accepted only for being near the dead-reckoned pose) is followed only when it corrects the
  //     prediction by what this one step's odometry can have got wrong: within gate_sigmas of the step's own
  //     sigma (sigma_* of this increment), not of the uncertainty accumulated while dead-reckoning. A weak fit
  //     1.1 m / 0 deg from the prediction with 43 % inliers (intel scan 806) moved a dead-reckoned pose that was
  //     0.2 m from the truth 1.2 m away, and which place was re-acquired after that was decided by millimetres.
  //     false: the earlier behaviour (any weak fit within gate_sigmas of the accumulated uncertainty).
  bool weak_follow_step_only = true;
  // (2) a fit near the dead-reckoned pose ends POOR/LOST at once only when unrivalled: no other refined
  //     candidate of the same search, at another place (farther than rival_sep_xy_m or rival_sep_yaw_rad),
  //     explains nearly as much of the scan (within rival_margin of its inlier share; the margin the hypotheses
  //     need over their runner-up, confirm_margin). A comparable rival means the scan does not decide where the
  //     robot is: it stays POOR (dead-reckons), is not followed either, and the wide search's hypotheses compete
  //     over the next scans. < 0: off.
  double rival_margin = 0.1;
  double rival_sep_xy_m = 0.3, rival_sep_yaw_rad = 10.0 * M_PI / 180;
  // LOST (lost_after POOR scans) searches +-window_sigmas sigma of the dead-reckoned pose (capped at
  // reacquire_xy_m / reacquire_yaw_rad) as POOR does, the sigma growing with the motion since the last fit: with
  // the calibrated odometry the dead-reckoned pose stays near the truth through unmapped ground, and a wider
  // window only adds wrong places (intel scan 805: a lock 3.8 m off in ground the map does not cover, from a
  // dead-reckoned pose 1.5 m off). Off: LOST searches the whole re-acquisition window (the earlier behaviour).
  bool lost_window_from_sigma = false;
  // CPU while re-acquiring: the wide search (+-10 m / +-180 deg: 100-400 ms on the Radish logs) proposes new
  // hypotheses only after the robot has moved reacquire_search_every_m or turned reacquire_search_every_rad since
  // the last one (a scan from nearly the same pose proposes the same places); the hypotheses already held and the
  // fit around the dead-reckoned pose are still tried on every scan. 0 (default): every scan. Measured with 0.5 m /
  // 15 deg (fploc-real-track, covered ATE cm / ms per scan): freiburg-079 23.5 / 38.1 -> 39.0 / 10.6, fhw 5.9 /
  // 35.9 -> 5.9 / 25.2, csail 4.3 / 26.8 -> 4.3 / 20.7, intel and aces unchanged (9.9, 7.4): the CPU bound costs
  // freiburg-079 one more wrong lock in ground the map does not cover (scans 4440-4605), so it is off.
  double reacquire_search_every_m = 0, reacquire_search_every_rad = 15.0 * M_PI / 180;
  int reacquire_after = 1;  // POOR scans in a row after which a jump needs confirmation
  int reacquire_candidates = 4, max_hypotheses = 8, confirm_scans = 5;
  double confirm_margin = 0.1;
  // ... and lies within this many sigma (Mahalanobis, x y yaw) of the dead-reckoned pose (<= 0: no such check).
  // The sigma is the dead-reckoned uncertainty, on laser steps plus what the wheels' model would have added since
  // the last fit: laser steps that follow a wrong place are self-consistent, so their own sigma bounds nothing.
  // freiburg-079 (bench node, ref / off start, covered ATE): 74.6 / 79.1 -> 8.8 / 7.1 cm, false OK 9 / 9 -> 0 / 0:
  // at scan 4150, while the robot turned in place in a room the map covers in part, an aliased room 4.4 m away
  // kept fitting for five scans and was taken (off, 3: a wrong near fit at scan 4545 kept the right place out
  // of the bound and cost freiburg-079 23.5 -> 173.3 cm; that was before the laser odometry and the wheels' bound).
  // The other four logs unchanged in both rows.
  double confirm_within_sigmas = 3;
  // ... unless it has kept matching while the robot travelled far_confirm_travel_m since it was proposed, with a
  // mean inlier share of at least reacquire_strong_ratio (a kidnapped robot in mapped ground is found again; a
  // robot in ground the map covers in part, whose scans also half fit an aliased room, is not carried off).
  // < 0: never (a hypothesis beyond the bound is not taken).
  double far_confirm_travel_m = 1.0;
  double confirm_inlier_ratio = 0.7;  // mean inlier share a hypothesis needs to be taken (a jump needs more than tracking)
  double field_max_m = 1.0;  // distance field truncation (the map's DistanceField)
  // The published covariance (GridResult::covariance) is the fit's own (the inverse Hessian of the refinement:
  // every point an independent measurement with point_sigma_m) plus the map's, which every point of a scan
  // shares and which therefore does not average out over them: a wall lies somewhere in its cell, so
  // map_sigma_cells x the raster's resolution in x and y (1/sqrt(12): a uniform position within one cell), and
  // that over the scan's median range in yaw. Published only: the tracker's search windows and gates keep the
  // fit's covariance (the map's error is the same on the next scan, not a random walk to accumulate). 0: the
  // fit's alone (the earlier behaviour: x/y/yaw NEES median 23-75 against the Radish reference poses, ~3 when
  // consistent; the fit alone says 5-8 mm where the reference disagrees by several cm).
  double map_sigma_cells = 0.28867513459481287;  // 1 / sqrt(12)
  // A weak fit (inliers < min_inlier_ratio, followed only because it agrees with the prediction) is published
  // POOR: the map does not confirm the track there (the tracker follows it as before and counts it towards
  // LOST). false: published OK until lost_after of them in a row (the earlier behaviour).
  bool weak_fit_is_poor = true;
  // After the tracker leaves LOST on a single fit (a near fit that ends dead reckoning), the fits are published
  // POOR until they have earned what a re-acquisition hypothesis needs: confirm_scans fits in a row with a mean
  // inlier share of at least confirm_inlier_ratio (a confirmed hypothesis has, so it is OK at once).
  // freiburg-079 scans 4098-4111 and 4132-4146: LOST ended by fits with 51-66 % inliers 1.0-1.2 m from the
  // truth, published OK. After POOR only (a few unmatched scans, the dead-reckoned pose still near) the track is
  // OK at once: re-confirming there too cost intel POOR on 28 % of its covered scans instead of 11 % for one
  // false OK less over the five Radish logs. false: OK from the first such fit (the earlier behaviour).
  bool reconfirm_after_lost = true;
  // Online odometry calibration (odometry_calibration.h): every pair of consecutive scans both fitted with
  // >= min_inlier_ratio calibrates the wheels (yaw bias per metre, turn scale, translation scale); every
  // prediction (tracking, dead reckoning, hypotheses) uses the corrected increment. Off: the raw wheels.
  bool calibrate_odometry = true;
  OdometryCalibrationConfig calibration;
  // Laser odometry (laser_odometry.h): the increment between two scans measured by matching the scan to the
  // last few scans (a local map of the robot's own), used for the prediction instead of the (calibrated)
  // wheels' whenever the match holds; without wheel odometry it replaces the no-odometry prediction. Where the
  // building map does not explain the scans (rooms it saw only through a door) the dead-reckoned pose then
  // follows the walls the robot sees instead of the wheels' drift, so the place to re-acquire stays near the
  // prediction. A matched step's uncertainty: laser_sigma_* (base + k * |increment|); a failed match: the
  // wheels' sigma_*. Off: the wheels alone (the earlier behaviour). Radish, fploc-real-track, covered ATE cm
  // intel / aces / fhw / csail / freiburg-079: off 10.7 / 7.4 / 23.4 / 4.3 / 21.1, on (with laser_wide_retry)
  // 7.4 / 5.9 / 5.9 / 6.4 / 8.8 (docs/notes/real2d.md, ninth pass).
  bool laser_odometry = true;
  LaserOdometryConfig laser;
  double laser_sigma_xy_m = 0.02, laser_sigma_xy_per_m = 0.05;
  double laser_sigma_yaw_rad = 0.5 * M_PI / 180, laser_sigma_yaw_per_rad = 0.05, laser_sigma_yaw_per_m = 0.5 * M_PI / 180;
  // While re-acquiring on laser steps, the fit around the prediction is also tried in the window the wheels'
  // model would have grown since the last fit; there only an unrivalled fit with reacquire_strong_ratio of the
  // scan explained is taken (the pose the last fits left can be off by more than their covariance says).
  bool laser_wide_retry = true;
  // ... and so is a failed tracking fit right after a good one (with laser_wide_retry): a laser step can be wrong by
  // more than its sigma in a large turn (csail scan 48 of the off start: a 44 deg turn, the fit 0.41 m off the
  // laser prediction with 99 % of the scan explained, outside the laser window and the 2x retry). fploc-real-track,
  // csail covered ATE ref / off: 6.4 / 7.6 -> 5.0 / 3.4 cm; intel, aces, fhw unchanged, freiburg-079 ref unchanged.
  bool laser_track_retry = true;
  // While tracking on a matched laser step: a map fit farther than gate_sigmas from the laser prediction with an
  // inlier share below this is not taken (the prediction is kept, POOR, counting towards LOST as a failed fit; the
  // distance in this step's sigmas, also for a fit of the widened retry): where the map is wrong in part, a fit that
  // explains only part of the scan can pull the track off a laser step that is right (intel scans 703-706: 0.34 m,
  // published OK). Radish (fploc-real-track, covered ATE cm ref / off, intel / aces / fhw / csail / freiburg-079):
  // off 7.4/7.2, 5.9/6.0, 5.9/5.9, 5.0/3.4, 8.8/7.1 with 3 false OK; 0.6: 6.1/6.1, 6.2/6.3, 5.9/5.9, 5.0/3.4,
  // 7.9/7.1, none; 0.7 and 0.8 none either (docs/notes/real2d.md, sixteenth pass). <= 0: off.
  double laser_conflict_inlier_ratio = 0.6;
  // Global localization (start_global(): no start pose; and a kidnapped robot with global_after_lost_scans): every
  // scan is searched over the whole map (every known-free cell of set_free_space()'s grid, every yaw; the same
  // branch-and-bound search) for up to global_candidates distinct places; each that fits (>= min_inlier_ratio)
  // becomes a hypothesis tracked as the re-acquisition's are (the odometry, laser or wheels, and its own local fit;
  // dropped at its first failed fit). Nothing is published OK until one hypothesis dominates: it has matched
  // confirm_scans scans in a row over at least global_confirm_travel_m of travel (odometry) with a mean inlier share
  // of at least global_confirm_inlier_ratio, and every other hypothesis alive at another place (rival_sep_*) has a
  // mean lower by global_confirm_margin, however few scans it has matched (a place proposed late in a symmetric
  // building has not had the time to match as many). There is no dead-reckoned pose to gate on: a building whose
  // places look alike stays LOST until the robot has seen what tells them apart.
  int global_candidates = 8;
  int global_max_hypotheses = 16;
  double global_sep_xy_m = 0.3;  // the whole-map search's candidates are distinct when farther apart than this, or
  double global_sep_yaw_rad = 10.0 * M_PI / 180;  // than this in yaw
  double global_confirm_travel_m = 1.0;
  double global_confirm_inlier_ratio = 0.8;
  double global_confirm_margin = 0.1;
  // ... and leaves at least global_confirm_outlier_ratio times the leader's unexplained share of the scan
  // unexplained: a lead of 0.83 over 0.72 is no lead (aces: a corridor seen 180 degrees turned, the right place
  // the one the map covers in part), one of 1.0 over 0.88 is (0 of the scan unexplained against 12 %).
  // docs/notes/real2d.md, fortieth round. 0: off.
  double global_confirm_outlier_ratio = 2.0;
  // Kidnapped robot: after this many scans LOST (beyond lost_after), re-acquisition searches the whole map with the
  // global rule above instead of the window around the dead-reckoned pose (needs set_free_space()). 0: never.
  int global_after_lost_scans = 0;
  // A whole-map search (start_global, a kidnapped robot) that has taken no place after this much sensor time (the
  // scans' stamps: update(points, odom, stamp_s)) gives up: LOST with GridResult::global_gave_up, no whole-map search
  // on later scans (each costs the whole map's branch-and-bound) until set_initial_pose or start_global. A search
  // whose scans carry no stamp has no budget. 0: no budget.
  double global_budget_s = 300;
};

enum class GridStatus { kOk = 0, kPoor = 1, kLost = 2, kNotInitialised = 3 };

// A place global localization tracks (GridResult::places): its pose after this scan, the scans it has matched in a
// row since it was proposed, their mean and lowest inlier share, and the odometry's travel since then.
struct GridPlace {
  int id = 0;
  Pose2 pose;
  int hits = 0;
  double mean_inlier_ratio = 0, min_inlier_ratio = 0, travel_m = 0;
};

struct GridResult {
  Pose2 pose;
  GridStatus status = GridStatus::kNotInitialised;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // x, y, yaw
  int num_points = 0, num_inliers = 0;
  double inlier_ratio = 0, rms_m = 0;
  double search_xy_m = 0, search_yaw_rad = 0;  // the window searched
  int candidates = 0;
  bool wide_search = false;  // the wide re-acquisition search ran on this scan
  double score = 0;  // the best candidate's correlative score (0..1, prior-weighted)
  int iterations = 0;
  int refined = 0;  // candidates refined
  int hypotheses = 0;      // re-acquisition hypotheses tracked after this scan (while LOST)
  bool reacquired = false;  // this scan ended LOST with a confirmed hypothesis
  bool global = false;      // searching the whole map (start_global, or LOST for global_after_lost_scans): not OK
  std::vector<GridPlace> places;  // while global: the places tracked after this scan (before one is taken)
  double global_elapsed_s = 0;    // while global (or gave up): sensor time since the whole-map search started
  bool global_gave_up = false;    // the whole-map search ran out of global_budget_s without taking a place: LOST
  bool laser_step = false;  // the prediction came from the laser odometry (else the wheels)
  double laser_inlier_ratio = 0;  // the laser odometry's match (0 when it did not match)
  Pose2 laser_increment;          // its increment since the previous scan (on laser steps)
  // The odometry calibration after this scan (yaw bias [rad/m], turn scale error, translation scale, pairs used).
  double odom_bias_rad_per_m = 0, odom_turn_scale_error = 0, odom_scale = 1;
  int odom_pairs = 0;
};

class GridLocalizer {
 public:
  GridLocalizer(std::shared_ptr<const DistanceField> field, GridLocalizerConfig cfg = {});
  ~GridLocalizer();
  // (Re)start: the next scan is searched around `pose` with the initial uncertainty.
  void set_initial_pose(const Pose2& pose);
  // The map's known-free cells (a cell with a value that is not occupied), where a whole-map search may place
  // the robot: the occupancy grid the distance field was built from (same size, resolution and origin; throws
  // std::invalid_argument otherwise). Without it a whole-map search spans the field and places the robot anywhere.
  void set_free_space(const OccupancyGrid& grid);
  // (Re)start without a pose: global localization (the config's global_*): not OK until one place dominates.
  void start_global();
  bool initialised() const { return have_pose_; }
  // points: the scan's returns in the robot frame; odom: the wheel odometry pose at the scan's time (any
  // frame; only increments are used).
  GridResult update(const std::vector<Eigen::Vector2d>& points, const std::optional<Pose2>& odom);
  // ... with the scan's time [s] (any epoch, increasing): what global_budget_s is counted in.
  GridResult update(const std::vector<Eigen::Vector2d>& points, const std::optional<Pose2>& odom, double stamp_s);
  const GridLocalizerConfig& config() const { return cfg_; }

 private:
  GridResult step(const std::vector<Eigen::Vector2d>& points, const std::optional<Pose2>& odom);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  GridLocalizerConfig cfg_;
  bool have_pose_ = false;
};

// The returns of a planar scan (beam i at angle_min + i * increment, x forward) in the robot frame, for a
// laser mounted at (mount_x, mount_y, mount_yaw), upside down (its angles mirrored, as Laser2dConfig::upside_down):
// ranges outside [min, max] or non-finite are dropped.
std::vector<Eigen::Vector2d> scan_points(const std::vector<float>& ranges, double angle_min, double increment,
                                         double min_range, double max_range, const Pose2& mount = {},
                                         bool upside_down = false);

}  // namespace fploc::laser2d
