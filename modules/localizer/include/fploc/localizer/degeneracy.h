// Degeneracy and the published pose status (issue 12, "honest uncertainty").
//
// Each frame's honest covariance (optimizer/covariance.h) says what that frame alone fixes. Where the plan
// leaves a direction open (a long featureless wall or corridor) the frame fixes nothing along it, and what
// the localizer publishes there is dead reckoning: the constant-velocity prediction (matcher) and the
// window's velocity regularisation carry the pose, whose error grows with the time since the direction
// was last fixed, and faster the longer the velocity along it has not been seen. The window's own marginal
// covariance would hide that (its velocity terms "constrain" the open direction), so the published
// covariance is tracked here instead, with the velocity error as a second covariance W (vx, vy, yaw rate):
//
//   predicted  W- = (sqrt(W) + accel dt)^2, capped at max_velocity_error (the platform's speed)
//              P- = (sqrt(P) + sqrt(W-) dt)^2   standard deviations add (a held velocity error is not
//                                               averaged away); per direction of the basis that
//                                               diagonalises both
//   published  P  = per direction the tighter of P- and the frame's P_f (same basis trick): where the frame
//                   fixes the pose P = P_f (frames are NOT fused with each other: their plan errors are the
//                   same walls' errors, so fusing them would be overconfident), where it does not P = P-.
//              W  = the tighter of W- and what the frame observes: velocity_sigma_mps along the
//                   directions it fixes (consecutive fixes give the velocity), nothing along the others.
//
// Status: OK while the published 1-sigma along the weakest horizontal direction (the largest eigenvalue
// of the x/y block) stays below poor_sigma_m and the heading's below poor_sigma_rad; otherwise POOR, with
// a text naming the direction ("position open along 87 deg (1 sigma 0.31 m): the plan does not constrain
// it here"). The matcher's POOR/LOST stay as they are (LOST means lost, not merely uncertain). A fix is also
// published POOR when the innovation gate refuses it, while a re-acquired track is being confirmed
// (confirm_fixes), when under half of its points lie on the plan (weak_fit_ratio) and when the map says empty
// where many of them lie (max_contradicted; occupancy-map plans only), and, after any frame published other than
// OK, while a fix lies beyond the gate of the dead-reckoned pose (a pose published OK carried on by the LiDAR odometry
// since: dead_reckoning_gate_sigma; the Localizer runs that odometry), and while a re-acquisition has
// a second fit that explains nearly as many points (rival_ratio; the Localizer searches it) or that explains the scan
// otherwise (structure the fix leaves off the plan, while what it leaves off could stand in front of the walls:
// rival_min_gained, rival.h).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>

#include "fploc/matcher/types.h"
#include "fploc/optimizer/covariance.h"

namespace fploc::localizer {

struct UncertaintyConfig {
  bool enabled = true;                 // false: the matcher's covariance and status as they were
  optimizer::CovarianceConfig frame;   // the per-frame covariance
  // The platform (not the world): how well consecutive fixes give the velocity, how fast the velocity may
  // change where it is not seen, and the largest velocity error (its top speed).
  double velocity_sigma_mps = 0.05;
  double accel_sigma_mps2 = 0.5;
  double max_velocity_error_mps = 1.5;
  double yaw_rate_sigma_rps = 0.005;   // the IMU's yaw rate carries the heading
  double poor_sigma_m = 0.1;           // POOR beyond this 1-sigma along the weakest horizontal direction
  double poor_sigma_rad = 0.05;        // ... or in heading
  double max_gap_s = 2.0;              // a longer gap between frames restarts from the frame alone
  // Innovation gate: a fix (the frame's pose, update() with `fix`) whose Mahalanobis distance from the
  // tracked prediction (the last fix carried on with the matcher's twist: its velocity and the IMU's yaw
  // rate; covariance P- + P_f) exceeds gate_sigma (as the 3-DoF chi-square quantile of that many sigmas:
  // 3 -> 14.2) is refused: status POOR, the prediction and P- go on. 0: off.
  double gate_sigma = 3.0;
  // Re-acquisition: a fix taken where the position was unknown (the predicted 1-sigma above reacquire_sigma_m
  // in every horizontal direction: the start from an uncertain initial pose, after LOST, after a long POOR
  // stretch; not a corridor, which the frames kept fixing across) is one registration's answer in a wide
  // search, and a wrong place that explains the scan (a parallel corridor, a twin room) gives one as readily as
  // the right one. Published POOR ("re-acquired: k of N fixes agreeing") until confirm_fixes accepted fixes in a
  // row, each within the innovation gate of the track the ones before it started; a POOR/LOST or refused frame
  // starts the count again. As the grid localizer's confirm_scans. 0: off (a single fix is OK).
  int confirm_fixes = 5;
  double reacquire_sigma_m = 0.3;      // (3 sigma: a region of about 2 m, where office aliases lie)
  // A weak fix (a share of its points within the matcher's inlier distance of the plan below weak_fit_ratio,
  // kept by the matcher, whose own limit is lower) is published POOR ("weak fit: k % of the points on the plan"):
  // the plan explains less than half of what the sensor sees there. The grid localizer's min_inlier_ratio and
  // weak_fit_is_poor. Status only. 0: off.
  double weak_fit_ratio = 0.5;
  // Free-space contradiction (a plan from an occupancy map, which also says where it is empty: update()'s
  // `contradicted`): of the fix's points the map has an opinion about, those on the plan (within the inlier
  // distance) and those in its known free space (farther than that from any occupied cell), the share in free
  // space. Above max_contradicted the fix is published POOR ("the map says empty where k % of the points it
  // knows lie"). Points in unknown space or off the map count for neither: a room the map saw only in part
  // leaves the fix a weak fit, not a contradicted one; a fix slid onto a wrong place puts its unmatched points
  // where the map saw nothing. A quarter: a correct pose's contradictions are the few people, doors and
  // furniture moved since the map was made. Status only. 0 or above 1: off.
  double max_contradicted = 0.25;
  // Odometry (the robot's own, e.g. its wheels: update()'s `motion`): the prediction is the tracked pose composed
  // with the increment, as the matcher predicts with it, whatever the time between frames (2D laser logs have
  // frames seconds and a metre apart), and P grows by the step's own 1-sigma instead of the velocity model's
  // (x/y, yaw as MatcherConfig::odom_sigma_*: the Localizer copies the matcher's).
  double odom_sigma_m = 0.05, odom_sigma_per_m = 0.3;
  double odom_sigma_rad = 2.0 * M_PI / 180, odom_sigma_per_rad = 0.3, odom_sigma_rad_per_m = 3.0 * M_PI / 180;
  // Dead reckoning (the Localizer's; update()'s `dead_reckoned`): after a stretch not published OK (POOR, LOST, a
  // re-acquisition) the track may come back on a wrong place that explains the scan as well as the right one (shelf
  // faces on the walls behind them, a corridor whose outer wall is glass), and the innovation gate cannot refuse it,
  // its prediction having grown to metres; and a track published OK may slide along a corridor a little per frame,
  // each step within the innovation gate. The Localizer runs a LiDAR odometry over every frame (frame-to-local-map
  // ICP on the same features, odometry/odometry.h, every k-th point so that about dr_max_points are used) and keeps
  // the frames published OK outside a stretch of the last dr_history_s as anchors: an anchor's fix carried on by the
  // odometry's motion since is a dead-reckoned pose. A fix (published OK so far) beyond dead_reckoning_gate_sigma (as
  // gate_sigma: the 3-DoF chi-square quantile; the covariance the fix would be published with plus the dead-reckoned
  // one) of it is published POOR ("N m from the dead-reckoned pose") with the offset's second moment added to its
  // covariance. Outside a stretch the fixes are checked against the oldest anchor (a slide drifts away from it); a
  // stretch freezes its anchor at its start (after a fix refused so, the anchor it was refused against; else the one
  // whose covariance grown by the odometry's error since is the smallest: the last OK frame is often one the tracker
  // carried along an open direction, its 1-sigma near poor_sigma_m, while one the plan fixed a second before is
  // better known; the odometry then goes on with that anchor's velocity) and lasts until confirm_fixes fixes in a row
  // lie within the gate. The dead-reckoned covariance: the anchor's published one plus the odometry's error, the
  // 1-sigma dr_sigma_m + dr_sigma_per_m * path length in x/y and dr_sigma_rad + dr_sigma_per_rad * turn +
  // dr_sigma_rad_per_m * path in yaw, plus, along each direction the odometry's own registration leaves open (its
  // 1-sigma from its points above poor_sigma_m), velocity_sigma_mps times the frame interval. 0: off.
  // A frame the odometry cannot register, or over which its velocity changes by more than dr_jump_mps (the ICP caught
  // another minimum; a platform changes its velocity by a few cm/s per frame, the odometry's noise adds ~0.1 m/s),
  // starts it again at that frame: the anchors before are dropped (no check until the next OK frame). Inside a stretch
  // that refused a fix against the dead-reckoned pose, that restart leaves the stretch nothing to end against: the
  // Localizer then searches a second fit near the next OK fix (as a re-acquisition's), and one explaining at least as
  // many points as the fix makes the stretch's end a re-acquisition (restart_confirmation()); else the stretch ends on
  // the fix, as before (corridor s1 mixed published a pose OK 2.3 m off where a fit 1.9 m away explained 1.3x as many
  // points; a stretch's end delayed always, by confirm_fixes, made corridor s3 crowd-15's dead reckoning drift among
  // people through a later stretch: right poses POOR 2 -> 24 %).
  // The odometry keeps only static points (OdometryConfig::static_support_m = dr_static_support_m: a map point another
  // keyframe saw on the same line; the walking people a crowd leaves in its map are not registered against) and holds
  // the constant-velocity prediction as a prior (OdometryConfig::prediction_sigma_m / _rad = dr_prediction_sigma_m /
  // _rad per frame): along a direction its points leave open it carries the velocity, as the covariance assumes,
  // instead of sliding where a passing person pulls it.
  // A stretch in which a fix was refused so ends only with confirm_fixes fixes in a row within dr_confirm_gate_sigma
  // (the same chi-square quantile) of the dead-reckoned pose, each published POOR until then: a track that slid comes
  // back to the gate's edge a little at a time, and the fix at the edge is no better than the one refused before it.
  // The IMU's gyro (the Localizer's add_imu samples, when it has them): the odometry's yaw change from one frame to
  // the next is the gyro's integral, held with this 1-sigma per frame (Odometry2D::set_yaw_change). People walking
  // beside the robot turn the ICP with them, by degrees over a stretch (0.1 m per 1 deg and 6 m travelled); a gyro
  // they cannot turn. 0: off (the ICP's own yaw, with the prediction's prior). On the corridor crowd's worlds the
  // right poses published POOR fall from 9-23 % to 0.5-4.8 %; on the mixed corridors one pose (s1) is published OK
  // 2.3 m off with it, 24 (s2) without it (docs/notes/realism.md, thirty-second round).
  double dr_gyro_sigma_rad = 0.002;
  double dead_reckoning_gate_sigma = 3.0;
  double dr_confirm_gate_sigma = 2.0;
  double dr_jump_mps = 0.5;
  int dr_max_points = 250;
  double dr_history_s = 2.0;
  double dr_static_support_m = 0.05;
  double dr_prediction_sigma_m = 0.01, dr_prediction_sigma_rad = 0.005;
  double dr_sigma_m = 0.02, dr_sigma_per_m = 0.02;
  double dr_sigma_rad = 0.5 * M_PI / 180, dr_sigma_per_rad = 0.02, dr_sigma_rad_per_m = 0.5 * M_PI / 180;
  // A second fit of a re-acquisition (the Localizer's, while the tracker confirms one: `confirming`): the frame
  // registered from starts around the fix (rings of rival_search_m and half of it); the best fit more than
  // rival_distance_m / rival_distance_rad from the fix is carried with the track (its offset in the fix's frame)
  // and registered again on every frame until the fix is confirmed. While it explains at least rival_ratio as many
  // points as the fix (within the matcher's inlier distance), the place is ambiguous (a cabinet's face on a drawn
  // wall 0.4 m along a corridor): published POOR ("a second fit ... explains N % as many points"), the offset's
  // second moment added to the covariance, and the confirmation starts again, unless the dead-reckoned pose tells
  // them apart (the fix within its gate, the rival beyond). The registrations use the Localizer's MatcherConfig.
  // 0: off.
  double rival_ratio = 0.8;
  // ... or while a second fit within rival_search_m explains the scan otherwise (rival.h): it puts at least
  // rival_min_gained points on one plan element that the fix leaves off the plan (structure, not chance hits), and of
  // the points it leaves off that the fix puts on, at most rival_max_behind_share lie beyond a drawn wall seen from it
  // (clutter stands in front of walls). Among the search's fits the one with most inliers that does so is the rival; a
  // carried rival that is neither is searched again. -1: the matcher's min_inliers (the fewest points it takes as a
  // fit; the Localizer copies it); 0: off (rival_ratio alone).
  int rival_min_gained = -1;
  double rival_max_behind_share = 0.1;
  double rival_search_m = 1.0;
  double rival_distance_m = 0.25, rival_distance_rad = 5.0 * M_PI / 180;
  // A fix beyond the dead reckoning's gate (dead_reckoning_gate_sigma) is registered again from the dead-reckoned
  // pose (the Localizer's, with the matcher's tracking gate): where that fit lies within the gate and explains at
  // least dr_refit_ratio as many points as the fix, it replaces the fix for the frame (the tracker, the window, and so
  // the pose fed back to the matcher). The matcher tracks inside its gate from its own last pose, so a fix that slid
  // onto a look-alike (cabinet faces meeting a bent wall 1.6 m along a corridor) stays there while the odometry holds
  // the truth and a fit from it explains more of the scan. Not where the robot's odometry predicts the frame
  // (Localizer::add_odometry). 0: off.
  double dr_refit_ratio = 1.15;
  // While the matcher is LOST the frame is registered from the dead-reckoned pose too (the same tracking gate and
  // ratio, against the matcher's stale pose): an OK fit within the dead reckoning's gate goes to the window as a POOR
  // frame (the window restarts there; published LOST, "re-seeded from the dead reckoning") and the matcher is started
  // again there (Localizer::take_reseed; the optimizer node's `reseed` output, FPLOC_RESEED in the graphs). A lost
  // matcher does not move with the robot and takes no refined pose; the relocalizer searches around the last good
  // pose, which the robot left behind long ago after seconds of LOST frames. Off with dr_refit_ratio 0, and where the
  // robot's odometry predicts the frame (as the refit); the optimizer node turns it off when its `reseed` output is
  // not connected.
  bool dr_reseed_when_lost = true;
  // A stretch's frozen anchor grows the dead-reckoned covariance with the path (dr_sigma_per_m), whatever the fixes in
  // it say: a stretch of right fixes published POOR only for their weak fit (a wall moved 0.2 m leaves 31-41 % of the
  // points on the plan) made the claimed 1-sigma 0.25 m after 14 s while the dead reckoning was 0.01-0.07 m off, and a
  // re-acquired fix 0.4 m off then passed its gate (corridor s3 mixed with the column rule). A weak fit (the tracker's
  // `weak_fit`: POOR for that alone) within dr_weak_fit_sigma (as gate_sigma: the 3-DoF chi-square quantile) of the
  // dead-reckoned pose bounds it: the anchor moves to the dead-reckoned pose itself, its covariance the tighter of the
  // dead-reckoned one and the fix's plus their offset's second moment. The pose is the odometry's, not the fix's (a weak
  // fit may be held off by cabinet faces; a dead reckoning moved to such fits published corridor s2 shelves OK 0.44 m
  // off); only its claimed uncertainty is bounded by what the two agree on (a fix off by d leaves it at least d).
  // 0: off.
  double dr_weak_fit_sigma = 1.0;
};

// A frame's pose dead-reckoned from the pose last published OK, with its covariance (x, y, yaw).
struct DeadReckoned {
  Pose2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

struct UncertaintyState {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // published (x, y, yaw)
  matcher::FitStatus status = matcher::FitStatus::kOk;
  std::string text;                    // why POOR (empty when OK)
  double sigma_max_m = 0;              // 1-sigma along the weakest horizontal direction
  double weak_direction_rad = 0;       // that direction (plan frame, -pi/2 .. pi/2]
  double sigma_yaw_rad = 0;
  double frame_sigma_max_m = 0;        // the frame's own 1-sigma along its weakest horizontal direction
  bool frame_degenerate = false;       // the frame alone leaves a direction open (frame sigma > poor_sigma_m)
  double innovation_sigma = 0;         // Mahalanobis distance of the fix from the prediction (0: not tested)
  bool refused = false;                // the fix failed the innovation gate
  double dead_reckoned_sigma = 0;      // Mahalanobis distance of the fix from the dead-reckoned pose (0: not tested)
  bool off_dead_reckoning = false;     // the fix failed that gate (published POOR)
  bool confirming = false;             // a re-acquisition being confirmed (confirm_fixes)
  bool weak_fit = false;               // published POOR for its weak fit alone (weak_fit_ratio): otherwise an OK fix
};

class UncertaintyTracker {
 public:
  explicit UncertaintyTracker(UncertaintyConfig cfg = {}) : cfg_(std::move(cfg)) {}
  // One frame, in time order: its own covariance (frame_valid false: the frame fixes nothing) and the
  // matcher's status/text. Returns what to publish with the frame's pose.
  // With `fix` (the frame's own pose, that P_f is about) and the matcher's body twist of the frame (its
  // motion model, carried to the next frame) the innovation gate applies (see gate_sigma); inlier_ratio is the
  // fix's share of points on the plan (weak_fit_ratio). motion: the robot's odometry increment since the
  // previous update (in that frame's body frame), if any: it predicts instead of the twist (odom_sigma_*).
  // contradicted: the fix's free-space contradiction share (max_contradicted; 0 without a free space).
  UncertaintyState update(int64_t utime, const Eigen::Matrix3d& frame_cov, bool frame_valid, matcher::FitStatus matcher_status,
                          const std::string& matcher_text = {}, const Pose2* fix = nullptr,
                          const matcher::Twist2* twist = nullptr, double inlier_ratio = 1.0,
                          const Pose2* motion = nullptr, double contradicted = 0.0,
                          const DeadReckoned* dead_reckoned = nullptr);
  // A frame since the last one published OK was not (POOR, LOST, re-acquired): a stretch whose fixes the caller checks
  // against the dead-reckoned pose of one anchor (dead_reckoning_gate_sigma) until confirm_fixes agree. A fix given a
  // dead-reckoned pose is checked against it in or out of a stretch.
  bool wants_dead_reckoning() const { return cfg_.dead_reckoning_gate_sigma > 0 && not_ok_since_ok_; }
  // The current stretch refused a fix against the dead-reckoned pose (the two disagree).
  bool refused_in_stretch() const { return wants_dead_reckoning() && dr_refused_; }
  // The re-acquisition is not confirmed yet (an ambiguity the caller found): confirm_fixes more fixes needed.
  void restart_confirmation() {
    if (cfg_.confirm_fixes > 0) confirming_ = true, agreeing_ = 0;
    not_ok_since_ok_ = true;
  }
  // A new initial pose with its uncertainty (1-sigma x/y and yaw); the velocity is unknown.
  void reset(double sigma_m, double sigma_rad);
  void reset() { have_ = false; }
  const UncertaintyConfig& config() const { return cfg_; }

 private:
  UncertaintyConfig cfg_;
  bool have_ = false;
  int64_t last_utime_ = 0;
  Eigen::Matrix3d P_ = Eigen::Matrix3d::Identity();   // pose (x, y, yaw)
  Eigen::Matrix3d W_ = Eigen::Matrix3d::Identity();   // velocity error (vx, vy, yaw rate)
  bool have_initial_ = false;                          // P_ / W_ hold reset()'s initial uncertainty
  bool have_mean_ = false;                             // the tracked pose and twist (innovation gate)
  Pose2 mean_;
  matcher::Twist2 twist_;
  bool confirming_ = false;                            // re-acquired: fixes in a row still to agree (confirm_fixes)
  int agreeing_ = 0;                                   // accepted fixes in a row since the re-acquisition
  int dr_agreeing_ = 0;                                // fixes in a row within the dead reckoning's gate
  bool dr_refused_ = false;                            // the current stretch refused a fix against the dead reckoning
  bool not_ok_since_ok_ = true;                        // a frame published other than OK since the last OK one (or none yet)
};

// The 3-DoF chi-square quantile with the probability of a 1-D Gaussian within k sigma (k = 3: 14.16).
double chi2_3dof_of_sigmas(double k);

// a - b as (x, y, yaw), the yaw wrapped; and d^T S^-1 d (S symmetric, by LDLT): the gates' Mahalanobis distances.
Eigen::Vector3d pose_difference(const Pose2& a, const Pose2& b);
double mahalanobis2(const Eigen::Vector3d& d, const Eigen::Matrix3d& S);

// The tighter of two covariances per direction of their common eigenbasis (generalised eigenvectors).
Eigen::Matrix3d tighter_of(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B);
// (sqrt(P) + sqrt(Q))^2 per direction of the basis that diagonalises both: standard deviations add.
Eigen::Matrix3d add_sigmas(const Eigen::Matrix3d& P, const Eigen::Matrix3d& Q);
// add_sigmas(P, diag(a)^2): every axis' standard deviation grows by its a.
Eigen::Matrix3d grow_linear(const Eigen::Matrix3d& P, const Eigen::Vector3d& a);
// Largest 1-sigma of the x/y block and its direction [rad, (-pi/2, pi/2]].
double weakest_horizontal(const Eigen::Matrix3d& P, double* direction_rad);
// Smallest 1-sigma of the x/y block.
double strongest_horizontal(const Eigen::Matrix3d& P);

}  // namespace fploc::localizer
