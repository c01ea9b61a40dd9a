// Windowed optimisation (paper Section IV-C, second stage). Keyframes are selected by distance/angle
// from the last key pose (single-frame poses); a window of the W most recent keyframes is optimised
// jointly with Ceres: the floor-plan terms of every keyframe (as in single-frame registration) plus the
// regularisation of consecutive linear and angular velocities, alpha ||v^{m+1} - v^m||^2 and
// beta ||w^{m+1} - w^m||^2. Each key pose is optimised W times and becomes final when it leaves the
// window. Non-keyframes are passed on with the correction (final - single-frame) of the surrounding
// keyframes interpolated in time, so the final trajectory has every frame.
// A fixed lag in time besides (max_final_delay_s): a frame whose key has not left the window when the
// newest frame is max_final_delay_s newer is made final then, with the window's current estimate (the key
// stays in the window for the keys after it; only its published pose stops changing). W keys span W
// keyframe intervals: 9-10 s for a standing robot, 2-5 s at the paper's 0.3-1 m/s.
//
// Motion compensation, as in the matcher: a key pose is the pose at its sweep's reference time
// tau = utime + t_ref (t_ref = the mean point time; the sweep is de-skewed there with the matcher's twist),
// the velocities are taken between those times, and every output pose is carried back from tau to its
// utime along the output trajectory: interpolated between the previous frame's pose at its tau and this
// one's (utime lies between them), exactly as the matcher's constant twist does for single-frame poses.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "fploc/matcher/lookup.h"
#include "fploc/matcher/as_built.h"
#include "fploc/matcher/assignment.h"
#include "fploc/matcher/types.h"

namespace ceres {
class CostFunction;
}  // namespace ceres

namespace fploc::optimizer {

struct OptimizerConfig {
  int window = 10;                     // W
  double alpha = 1.1;                  // linear velocity regularisation
  double beta = 0.9;                   // angular velocity regularisation
  bool body_frame_velocity = false;    // regularise body-frame velocities (constant-speed turns cost nothing)
                                       // instead of the paper's world-frame ones
  double keyframe_distance_m = 0.1;
  double keyframe_angle_rad = 5.0 * M_PI / 180;
  double gate_m = 0.3;                 // correspondence gate around the current estimate
  double loss_scale_m = 0.05;
  std::string loss = "cauchy";    // as MatcherConfig::loss
  int max_iterations = 10;             // Ceres iterations per outer round
  int rounds = 2;                      // look-up + solve rounds per new keyframe
  bool group_rule = true;
  int stride = 1;                      // use every stride-th feature point of a keyframe
  int max_points = 800;                // per keyframe: the stride grows to keep about this many (0 = all)
  bool budget_weight = true;           // weight the sampled points by the stride (estimate of the sum over all)
  int element_quota = 0;               // as MatcherConfig::element_quota (0 = off)
  double askew_max_m = 0;              // as MatcherConfig::askew_max_m, judged at a key's first look-up (0 = off)
  double relook_m = 0.01;              // a key's correspondences are looked up again when it moved this far
  double relook_rad = 0.2 * M_PI / 180;  // ... or turned this much since the last look-up
  bool anchor_final = false;           // also regularise against the last two final key poses (held fixed)
  double max_keyframe_gap_s = 2.0;     // a longer gap (e.g. lost frames) restarts the window
  double keyframe_interval_s = 1.0;    // also a keyframe when the last is this old, so a standing robot's
                                       // final poses keep coming (they wait for keys); 0 = distance/angle only
  // A frame's final pose is out at the latest when the newest frame is this much newer (FPLOC_POSE lags the
  // sensor by at most this plus the time to the next frame): a key still in the window goes out with its
  // current estimate (optimised fewer than W times), a non-keyframe with the correction interpolated between
  // its keys' current estimates (held from the key before it while none follows). 0 = when its key leaves
  // the window (W keyframe intervals: 9-10 s standing).
  double max_final_delay_s = 1.0;
  // z at the end of a dead-reckoned stretch (end_z_stretch: a lift ride's z integrated from the IMU, whose
  // sigma grew): a frame whose z is known with a sigma below 1 / z_stretch_ratio of the previous known one's
  // (which is above z_stretch_min_sigma_m) moves the stretch's frames that are not final yet by its innovation
  // (its z - the previous z), each by the share its own sigma had grown (0 at the stretch's start, all of it at
  // its end: the error of an integrated bias grows as the sigma the IMU's height is given). A fixed-lag
  // smoother's correction, within max_final_delay_s. Internal; z_stretch_ratio 0 = off.
  double z_stretch_ratio = 3;
  double z_stretch_min_sigma_m = 0.02;
  std::string linear_solver = "sparse";  // "sparse" (SPARSE_NORMAL_CHOLESKY) or "dense" (DENSE_NORMAL_CHOLESKY)
  // Each keyframe's floor-plan term in the compact square-root form (matcher::add_frame_term): the same
  // steps, 4 residuals per keyframe instead of one per point (then the dense solver is the cheaper one).
  bool compact_terms = true;
  const std::vector<float>* element_weight = nullptr;  // as MatcherConfig::element_weight
  matcher::AsBuiltModel as_built;      // as MatcherConfig::as_built (with compact_terms or not: always compact)
  // Published covariance: FrameInput::covariance (of the frame's single-frame fix) plus d d^T, d the output
  // pose minus that fix (the window's pose is not the fix the covariance is about).
  bool covariance_offset = true;
  // A pose published OK whose covariance (with the offset above) has a 1-sigma beyond this along its weakest
  // horizontal direction is published POOR ("window pose d m from the frame's fix"): the window and the
  // fix disagree by more than the fix's uncertainty allows. 0: off (localizer::Localizer sets it to its
  // uncertainty.poor_sigma_m).
  double poor_sigma_m = 0;
};

struct FrameInput {
  FeatureFrame features;               // as measured (not de-skewed)
  Pose2 sfr;                           // single-frame registration result at features.utime
  matcher::Twist2 twist;                        // the matcher's body twist (its motion compensation)
  matcher::FitStatus status = matcher::FitStatus::kOk;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // published with the frame's pose
  // What to publish besides (localizer/degeneracy.h): a status that only downgrades `status` (POOR where
  // the plan leaves a direction open) and why. Keyframes are still chosen by `status` alone.
  matcher::FitStatus published_status = matcher::FitStatus::kOk;
  std::string status_text;
};

struct PoseOut {
  int64_t utime = 0;
  int64_t scan_seq = 0;
  Pose2 pose;
  double roll = 0, pitch = 0, z = 0;
  bool keyframe = false;
  bool final_estimate = false;
  matcher::FitStatus status = matcher::FitStatus::kOk;
  std::string status_text;             // why not OK
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // (x, y, yaw): FrameInput::covariance (+ d d^T, see config)
  double z_sigma = 0, roll_pitch_sigma = 0;  // the frame's own (as measured; "unknown" sigmas, see types.h)
  int optimised = 0;                   // how many window solves this pose took part in
};

class WindowOptimizer {
 public:
  WindowOptimizer(const matcher::NearestLookup& lookup, OptimizerConfig cfg);
  ~WindowOptimizer();
  // Feeds one frame (in time order). Appends the poses that became final (time order) to `finals` and
  // returns the current estimate of this frame (final_estimate = false).
  PoseOut add(FrameInput in, std::vector<PoseOut>* finals);
  // Makes everything still in the window final (end of a sequence).
  void flush(std::vector<PoseOut>* finals);
  // flush(), and the next frame starts a new track: nothing of the old one (its correction, its final poses as
  // anchors) carries over (a long keyframe gap does the same; the Localizer after re-seeding a lost matcher).
  void restart(std::vector<PoseOut>* finals);
  // The z of a frame about to come ends a dead-reckoned stretch of z (OptimizerConfig::z_stretch_ratio): the
  // optimizer node calls it when a lift ride ends on another floor, before the window is made final there.
  // (Not in add(): a held prediction's sigma grows too, but its error is no integrated bias.)
  void end_z_stretch(const FeatureFrame& f);
  size_t window_size() const { return window_.size(); }
  int solves() const { return solves_; }
  const OptimizerConfig& config() const { return cfg_; }

 private:
  // A frame's single-frame result at its sweep's reference time.
  struct Frame {
    FrameInput in;
    double t_ref = 0;                  // [s after utime]
    int64_t tau = 0;                   // utime + t_ref [us]
    Pose2 sfr_tau;                     // the single-frame pose at tau
  };
  struct Key {
    Frame f;
    FeatureFrame deskewed;             // features de-skewed to t_ref
    double x[3];                       // pose at tau
    Pose2 pose_tau() const { return {x[0], x[1], wrap_angle(x[2])}; }  // the current estimate, yaw wrapped
    int optimised = 0;
    bool out = false;                  // its final pose is out (max_final_delay_s) while it is still in the window
    std::vector<matcher::Assignment> as;        // correspondences, looked up at as_pose
    Pose2 as_pose;
    bool as_valid = false;
    int as_stride = 1;
    // The points its look-ups use (matcher::select_points at its first look-up: the per-element budget).
    std::vector<matcher::SampledPoint> sel;
    bool sel_valid = false;
    // The floor-plan term of `as`, prepared at as_pose (matcher::make_frame_term): kept across rounds and
    // solves while the correspondences hold, re-built with them.
    std::shared_ptr<ceres::CostFunction> term;
  };
  struct Final {
    int64_t tau;
    Pose2 pose_tau;
    Eigen::Vector3d correction;        // pose_tau - sfr_tau
  };
  struct Stamped {
    bool valid = false;
    int64_t tau = 0;
    Pose2 pose;
  };
  void solve();
  void finalize_front(std::vector<PoseOut>* finals);
  void emit_pending_until(int64_t tau, const Eigen::Vector3d& corr_next, std::vector<PoseOut>* finals);
  // Makes the frames up to utime `until` final that are not yet (keys still in the window: their current
  // estimate), in time order.
  void finalize_until(int64_t until, std::vector<PoseOut>* finals);
  void emit_final(const Frame& f, const Pose2& pose_tau, bool key, int optimised, std::vector<PoseOut>* finals);
  // The output pose at utime from the pose at tau and the previous output's pose at its tau (`prev`,
  // updated), which closes the interval [prev.tau, tau] containing utime; without one (start, gap) the
  // matcher's twist carries the pose back.
  PoseOut make_out(const Frame& f, const Pose2& pose_tau, bool key, Stamped* prev) const;
  // Roll/pitch/z at the frame's utime: interpolated between the nearest frames that have them (they
  // hold at utime + attitude_t, mid-sweep); held at the ends when the frame's own are unknown.
  void fill_gravity(PoseOut* o, const FeatureFrame& f) const;
  Eigen::Vector3d newest_correction() const;

  const matcher::NearestLookup& lookup_;
  OptimizerConfig cfg_;
  std::deque<Key> window_;
  std::deque<Frame> pending_;          // non-keyframes waiting for their surrounding keyframes to be final
  std::deque<Final> finals_;           // last two final key poses
  Stamped last_final_, last_latest_;   // previous pose at tau of the final / latest output streams
  struct Gravity {
    int64_t t;                         // when roll/pitch/z hold (utime + attitude_t)
    double roll, pitch, z;
    bool rp_known, z_known;
    double z_sigma;
  };
  std::deque<Gravity> gravity_;        // recent frames' roll/pitch/z
  bool have_last_key_ = false;
  Pose2 last_key_sfr_;
  int64_t last_key_utime_ = 0;
  int solves_ = 0;
};

}  // namespace fploc::optimizer