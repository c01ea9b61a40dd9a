// The IMU's vertical motion (a lift ride): the specific force along gravity, integrated twice between
// two rests. No LCM; fed with raw accelerometer samples (sensor frame, m/s^2).
//
// The vertical acceleration is |f| - g0, where g0 is the magnitude of the specific force measured at rest
// (a running mean while the IMU is quiet and not riding: it absorbs the accelerometer's bias along the
// vertical and the local gravity). |f| rather than a projection: in a lift the acceleration is along
// gravity, so the direction of f does not change, only its length, and a tilted sensor changes nothing.
// Horizontal driving changes |f| by a_h^2 / 2g (under 1 cm/s^2 at 0.4 m/s^2): below the quiet threshold.
//
// Rest: the (0.05 s low-passed) vertical acceleration stays within quiet_accel for quiet_s while the
// integrated velocity is small; at rest the velocity and height are zeroed (zero-velocity update). A
// ride starts when the integrated velocity or height leaves the start thresholds, and ends at the next
// rest: its height change is reported once by take_ride(). When a rest ends, g0 becomes the mean |f| over
// that rest and the motion is integrated from where the acceleration really began (the quiet test needs
// the ride's first, slow part of the jerk-limited profile to pass before it notices: without this the
// ride's start and a g0 learned while driving (|f| grows by a_h^2 / 2g) cost ~3 % of a 3.2 m ride).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>

namespace fploc::localizer {

struct VerticalImuConfig {
  double quiet_accel_mps2 = 0.05;   // |low-passed vertical acceleration| below this: quiet
  double quiet_s = 0.5;             // quiet this long (and velocity below rest_speed) = at rest
  double rest_speed_mps = 0.15;     // |integrated velocity| below this counts as at rest when quiet
  double start_speed_mps = 0.1;     // a ride starts when |v| exceeds this ...
  double start_height_m = 0.1;      // ... or |height| exceeds this
  double lowpass_s = 0.05;          // time constant of the low-pass for the quiet test
  double gravity_tau_s = 2.0;       // time constant of the running mean of |f| at rest
  double max_gap_s = 0.2;           // a longer gap between samples resets the integration
  double max_ride_s = 120;          // a "ride" longer than this is not one (reset)
  // Leaving a rest: g0 is the mean |f| over that rest (standing still: the best calibration there is), less
  // its last `rest_guard_s` (the ride may already have begun below the quiet threshold), and the integration
  // restarts from the last sample whose low-passed acceleration was below still_frac x quiet_accel.
  double rest_guard_s = 0.3;
  double rest_window_s = 2.0;      // (the rest's last 2 s: a long quiet stretch may have begun while driving)
  double still_frac = 0.25;
  double history_s = 1.0;
};

struct VerticalRide {
  int64_t start_utime = 0, end_utime = 0;
  double height_m = 0;              // up positive
  double peak_speed_mps = 0;
};

class VerticalImu {
 public:
  explicit VerticalImu(VerticalImuConfig cfg = {}) : cfg_(cfg) {}
  // One sample (utime in us, specific force in the sensor frame). Non-finite or out-of-order samples
  // are ignored.
  void add(int64_t utime, const Eigen::Vector3d& accel);
  // Forget the integration (the sensor left the lift area, a gap, ...); the gravity estimate stays.
  void reset();

  bool riding() const { return riding_; }
  int64_t ride_start_utime() const { return ride_start_; }  // while riding
  int64_t last_utime() const { return last_utime_; }
  double height() const { return h_; }              // since the last rest [m]
  double velocity() const { return v_; }            // [m/s]
  bool has_gravity() const { return have_g_; }
  double gravity() const { return g0_; }
  // The last completed ride, once (nullopt when none finished since the last call).
  std::optional<VerticalRide> take_ride();

 private:
  VerticalImuConfig cfg_;
  bool have_last_ = false, have_g_ = false, riding_ = false;
  int64_t last_utime_ = 0, ride_start_ = 0;
  double g0_ = 0, lp_ = 0, quiet_for_ = 0, v_ = 0, h_ = 0, peak_ = 0;
  std::optional<VerticalRide> done_;
  struct Sample {
    int64_t utime;
    double n, lp;  // |f| and the low-passed vertical acceleration
    bool rest;
  };
  std::deque<Sample> hist_;
  bool was_rest_ = false;
  std::deque<Sample> rest_tail_;  // the rest's last rest_window_s + rest_guard_s
  void restart_from_rest();
};

}  // namespace fploc::localizer
