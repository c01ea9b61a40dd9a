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
// rest: its height change is reported once by take_ride().
#pragma once
#include <Eigen/Core>
#include <cstdint>
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
};

}  // namespace fploc::localizer
