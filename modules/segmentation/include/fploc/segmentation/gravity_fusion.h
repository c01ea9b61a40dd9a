// Roll/pitch against gravity from the planes and the IMU (issue 11 item 3: ramps and thresholds).
//
// The ceiling and ground planes give the sensor's attitude relative to the surfaces it sees, to a few
// hundredths of a degree; that is the attitude against gravity only when those surfaces are level. On a
// ramp under a ceiling parallel to it both planes tilt with the robot, and the planes alone cannot tell a
// robot on a 7 deg ramp from a level one. The IMU can: the gyro measures every rotation of the sensor, the
// accelerometer measures gravity (plus the platform's acceleration).
//
// The fusion keeps, in the sensor frame, the gravity up vector g and the surface's tilt o = g - p (p: the
// planes' up; both world-fixed vectors, carried between scans by the gyro rotation):
//  - LEVEL (o = 0): the output is the planes' attitude itself (bit-identical to the plane-only estimate).
//    The planes' up changing by more than the gyro says (their unexplained change, summed over the last
//    seconds) means the surface under/over the sensor changed: when that change is past `change_deg` and
//    the accelerometer's gravity (low-passed over ~1 s) agrees with it, the robot is on a slope (o = the
//    change the gyro carried across).
//  - SLOPE: g = p + o. While the planes move as the gyro says (the same surfaces), the planes carry the
//    robot's rotation and o stays; a step of the planes the gyro does not see (a fit moving to another
//    surface: the ramp's foot or head, the ceiling beyond) is carried by the gyro (o absorbs it); a step
//    smaller than change_deg (one scan's compromise fit) only once it persists max_hold_scans scans. The
//    accelerometer pulls o slowly (`accel_tau_s`) towards its gravity (platform accelerations average out).
//    o below `level_deg` again: back to LEVEL (said, never a silent jump). When that comes with a step of the
//    planes to another surface (the level floor behind the ramp's foot, the landing past its head: one
//    scan's fit of a surface often seen far away), gravity is the gyro's prediction pulled towards the planes
//    for `level_settle_s` (as on a slope), not the new planes as they are.
//  - No plane: g carried by the gyro (sigma grows with the gyro's noise and bias); no gyro: not handled
//    here (the caller holds the last estimate with a grown sigma).
// The disagreement between the planes and gravity is the floor's slope: slope_deg() (0 on level floors).
// Transport-free; Segmenter feeds it (segmenter_imu.cpp).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <string>
#include <utility>

namespace fploc::seg {

struct GravityFusionConfig {
  double change_deg = 1.5;       // unexplained change of the planes' up (leaky sum) that means another surface
  double change_leak_s = 3.0;    // time constant of that leaky sum (gyro drift and plane noise forgotten)
  double accel_agree_deg = 1.5;  // the accelerometer's tilt agrees with the gyro's to this (or half the change)
  double step_deg = 0.3;         // on a slope: a plane step larger than this (vs the gyro) is a surface change
  double level_deg = 0.4;        // on a slope: the surface tilt below this is level again
  int max_hold_scans = 3;        // level: planes off the gyro by more than step_deg: gyro-carried for at most this
                                 // (longer while the gyro is quiet: the sensor is not turning; standing still
                                 // the accelerometer holds it); slope: a plane step between step_deg and
                                 // change_deg is taken for another surface only after this many scans
  double accel_tau_s = 10.0;     // on a slope: the accelerometer's pull on the surface tilt
  double level_settle_s = 1.0;   // level again after a step of the planes to another surface (the ramp's foot or head):
                                 // for this long gravity is the gyro's prediction pulled towards the planes
                                 // (slope_plane_tau_s) instead of the planes as they are (0: at once)
  double slope_plane_tau_s = 0.25;  // on a slope: gravity is the gyro's prediction pulled towards planes + tilt with
                                   // this time constant (one scan's plane fit is a few tenths of a degree off where
                                   // the surfaces change under the robot; the gyro drifts ~0.03 deg/s)
  double accel_bias_tau_s = 30.0; // level floors: the accelerometer's tilt bias against the planes, low-passed
  double accel_bias_max_turn_rate = 0.02;  // rad/s: ... only while not turning (v w: 1.8 cm/s^2 at 0.9 m/s)
  double still_rate = 0.01;                // rad/s: every gyro sample of the interval below this (bias-corrected) ...
  double still_accel_dir = 0.0015;         // ... the specific force's direction within this (rad) of the stretch's start
  double still_accel_norm = 0.02;          // ... and its length within this (m/s^2) of the last scan's ...
  double still_s = 0.5;                    // ... for this long: standing still (the bias = the stretch's mean)
  double level_by_accel_deg = 2.0;         // on a slope of less than this, the low-passed accelerometer within
                                           // level_deg / 2 of the planes means level again (needs a calibrated bias)
  double accel_lp_tau_s = 1.0;   // low-pass of the accelerometer's gravity for the entry check
  double accel_norm_tol = 0.3;   // m/s^2: |mean specific force| this close to g to be used
  double gyro_noise = 0.0015;    // rad/s white noise per sample (sigma growth without planes)
  double gyro_bias_sigma = 0.0005;  // rad/s left after the bias estimate (sigma growth without planes)
  // A scan the gyro has not reached yet (its samples late, the stream live: some reach the last update): without
  // planes, and level with planes off the last gravity by more than change_deg (that gravity held for it),
  // nothing is updated, so the next scan's gyro spans both intervals and tells another surface from the sensor's
  // turn. Taken as level instead, a ramp's surface became gravity for the whole ramp. Up to this long after the
  // last update; beyond, as before (the IMU stopped).
  double late_gyro_hold_s = 0.5;
};

class GravityFusion {
 public:
  enum class Mode { kLevel, kSlope };
  struct Result {
    bool valid = false;       // false: nothing to say (no planes and no gyro, or not started)
    Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // gravity up in the sensor frame at the given time
    double sigma = M_PI;      // 1-sigma of the tilt [rad]
    bool from_planes = false; // the planes' own attitude (level surfaces), bit-identical
    bool predicted = false;   // no plane: carried by the gyro
    bool settling = false;    // level again after a step to another surface: the planes blended in
    bool held = false;        // the gyro late for this scan, the planes off the last gravity: that gravity held
    std::string text;         // what happened (empty: nothing new)
  };

  explicit GravityFusion(GravityFusionConfig cfg = {}) : cfg_(cfg) {}

  // Gyro sample (rad/s, sensor frame) at utime [us]: the mean rate over the interval since the previous sample
  // (a band-limited IMU output); out-of-order samples ignored, time going back resets.
  void add_gyro(const Eigen::Vector3d& rate, int64_t utime);
  bool has_gyro() const { return gyro_.size() >= 2; }
  // The sensor's rotation from time ta to tb (orientation at tb relative to ta, body frame; a world-fixed
  // vector v: v(tb) = R^T v(ta)), bias-corrected; false when the gyro does not cover [ta, tb].
  bool rotation(int64_t ta, int64_t tb, const Eigen::Vector3d& bias, Eigen::Matrix3d* R) const;

  // One scan at time t (the planes' time, mid-sweep): `plane_up` the planes' up (nullptr: no plane accepted),
  // its sigma; `accel` the mean specific force since the last scan (nullptr: none); `bias` the gyro bias.
  // `plane_repeated`: the planes are last scan's as they were (a fit that kept its start), in last scan's axes:
  // on a slope they are not a measurement of this scan (gravity carried by the gyro); level, taken as they are.
  Result update(int64_t t, const Eigen::Vector3d* plane_up, double plane_sigma, const Eigen::Vector3d* accel,
                const Eigen::Vector3d& bias, bool plane_repeated = false);

  Mode mode() const { return mode_; }
  // Gravity up in the sensor frame (false before the first update), carried by the gyro from the last update to
  // time t (this scan's mid-sweep: the sensor pitches a degree per scan over a ramp's head); as of the last update
  // where the gyro does not cover the interval (or it is over 1 s, as update() allows).
  bool gravity_up_at(int64_t t, const Eigen::Vector3d& bias, Eigen::Vector3d* up) const {
    if (!started_) return false;
    Eigen::Matrix3d R;
    *up = t > t_ && t - t_ <= 1'000'000 && rotation(t_, t, bias, &R) ? Eigen::Vector3d((R.transpose() * g_).normalized()) : g_;
    return true;
  }
  // The surface's tilt against gravity [deg] (0 on level floors): the floor's slope when the planes are the floor's.
  double slope_deg() const;

 private:
  GravityFusionConfig cfg_;
  std::deque<std::pair<int64_t, Eigen::Vector3d>> gyro_;
  // Gravity carried by the gyro alone over dt: its sigma grows with the bias and noise; r gets it.
  void carry_by_gyro(const Eigen::Vector3d& g_pred, double dt, Result& r);
  // The tilt's sigma after dt seconds without planes (gyro bias and noise).
  double sigma_after(double dt) const;
  // Gravity is the planes' up: the state takes it and r says so.
  Result& take_planes(const Eigen::Vector3d& up, double plane_sigma, Result& r);
  // Level again after a step to another surface: gravity the gyro's prediction pulled towards the planes (as on a
  // slope) until settle_until_, so that one scan's plane of the new surface does not pass into the attitude as it is.
  Result& settle_to_planes(const Eigen::Vector3d& g_pred, const Eigen::Vector3d& up, double plane_sigma, double dt,
                           Result& r);

  bool started_ = false;
  int64_t t_ = 0;
  Mode mode_ = Mode::kLevel;
  Eigen::Vector3d g_ = Eigen::Vector3d::UnitZ();   // gravity up (sensor frame, at t_)
  Eigen::Vector3d o_ = Eigen::Vector3d::Zero();    // surface tilt: g - p (world-fixed difference vector)
  Eigen::Vector3d u_ = Eigen::Vector3d::Zero();    // leaky sum of the planes' unexplained change (LEVEL)
  Eigen::Vector3d acc_lp_ = Eigen::Vector3d::UnitZ();  // accelerometer gravity, low-passed (gyro-carried)
  bool have_acc_lp_ = false;
  Eigen::Vector3d acc_bias_ = Eigen::Vector3d::Zero();  // accelerometer direction minus gravity on level floors
  int held_ = 0;             // scans carried by the gyro since the planes stepped (LEVEL)
  Eigen::Vector3d held_nu_ = Eigen::Vector3d::Zero();  // last scan's disagreement
  bool have_prev_acc_ = false;
  Eigen::Vector3d still_ref_ = Eigen::Vector3d::UnitZ();  // the specific force's direction when the stretch began
  double prev_acc_norm_ = 0;
  double still_run_ = 0;     // length of the current still stretch [s]
  Eigen::Vector3d still_sum_ = Eigen::Vector3d::Zero();  // its accelerometer-minus-planes directions (level floors)
  int still_n_ = 0;
  double still_s_ = 0;       // time spent standing still on level floors (> 0: the accelerometer's bias calibrated)
  bool refused_ = false;     // a change without the accelerometer's agreement was said (once per episode)
  double sigma_ = M_PI;      // tilt sigma of g
  double o_sigma_ = 0;       // of the surface tilt
  int64_t settle_until_ = 0; // LEVEL again after a step to another surface: the planes blended in until then
};

const char* to_string(GravityFusion::Mode m);

}  // namespace fploc::seg
