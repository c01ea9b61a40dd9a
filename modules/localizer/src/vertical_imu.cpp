#include "fploc/localizer/vertical_imu.h"

#include <cmath>

namespace fploc::localizer {

void VerticalImu::reset() {
  riding_ = false;
  v_ = h_ = peak_ = 0;
  quiet_for_ = 0;
  lp_ = 0;
}

std::optional<VerticalRide> VerticalImu::take_ride() {
  auto r = done_;
  done_.reset();
  return r;
}

void VerticalImu::add(int64_t utime, const Eigen::Vector3d& accel) {
  if (!accel.allFinite()) return;
  if (have_last_ && utime <= last_utime_) return;
  const double n = accel.norm();
  if (!have_last_) {
    have_last_ = true;
    last_utime_ = utime;
    if (!have_g_) g0_ = n, have_g_ = true;
    return;
  }
  const double dt = (utime - last_utime_) * 1e-6;
  last_utime_ = utime;
  if (dt > cfg_.max_gap_s) {
    reset();
    return;
  }
  const double a = n - g0_;
  lp_ += (a - lp_) * std::min(1.0, dt / cfg_.lowpass_s);
  quiet_for_ = std::abs(lp_) < cfg_.quiet_accel_mps2 ? quiet_for_ + dt : 0;
  // Trapezoid-free Euler: at 100-200 Hz the difference is far below the bias's effect.
  v_ += a * dt;
  h_ += v_ * dt;
  peak_ = std::max(peak_, std::abs(v_));
  const bool rest = quiet_for_ >= cfg_.quiet_s && std::abs(v_) < cfg_.rest_speed_mps;
  if (!riding_) {
    if (rest) {
      // Zero-velocity update; the running mean of |f| follows the bias (only while quiet).
      v_ = h_ = peak_ = 0;
      g0_ += (n - g0_) * std::min(1.0, dt / cfg_.gravity_tau_s);
    } else if (std::abs(v_) > cfg_.start_speed_mps || std::abs(h_) > cfg_.start_height_m) {
      riding_ = true;
      ride_start_ = utime;
    }
    return;
  }
  if (rest) {
    done_ = VerticalRide{ride_start_, utime, h_, peak_};
    riding_ = false;
    v_ = h_ = peak_ = 0;
  } else if ((utime - ride_start_) * 1e-6 > cfg_.max_ride_s) {
    reset();
  }
}

}  // namespace fploc::localizer
