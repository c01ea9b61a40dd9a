#include "fploc/localizer/vertical_imu.h"

#include <cmath>

namespace fploc::localizer {

void VerticalImu::reset() {
  riding_ = false;
  v_ = h_ = peak_ = 0;
  quiet_for_ = 0;
  lp_ = 0;
  hist_.clear();
  was_rest_ = false;
  rest_tail_.clear();
}

void VerticalImu::restart_from_rest() {
  // g0 from the rest just left (its last rest_window_s before the guard, at least 20 samples), else the
  // running mean.
  double sum = 0;
  int n = 0;
  const int64_t guard = hist_.empty() ? 0 : hist_.back().utime - int64_t(cfg_.rest_guard_s * 1e6);
  for (const auto& r : rest_tail_)
    if (r.utime <= guard) sum += r.n, ++n;
  if (n >= 20) g0_ = sum / n;
  // The last sample that was still (its low-passed acceleration well inside the quiet band): the ride began
  // after it.
  size_t start = hist_.size();
  for (size_t i = hist_.size(); i-- > 0;) {
    if (std::abs(hist_[i].lp) < cfg_.still_frac * cfg_.quiet_accel_mps2) {
      start = i;
      break;
    }
  }
  v_ = h_ = peak_ = 0;
  if (start >= hist_.size()) return;
  for (size_t i = start + 1; i < hist_.size(); ++i) {
    const double dt = (hist_[i].utime - hist_[i - 1].utime) * 1e-6;
    v_ += (hist_[i].n - g0_) * dt;
    h_ += v_ * dt;
    peak_ = std::max(peak_, std::abs(v_));
  }
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
  hist_.push_back({utime, n, lp_, rest});
  while (hist_.size() > 2 && hist_.front().utime < utime - int64_t(cfg_.history_s * 1e6)) hist_.pop_front();
  if (!riding_) {
    if (rest) {
      // Zero-velocity update; the running mean of |f| follows the bias (only while quiet), and the mean over
      // this rest (less its last rest_guard_s) is kept for the ride that may follow.
      v_ = h_ = peak_ = 0;
      g0_ += (n - g0_) * std::min(1.0, dt / cfg_.gravity_tau_s);
      if (!was_rest_) {
        // A new rest: its quiet stretch so far (the quiet_s that made it a rest) counts too.
        rest_tail_.clear();
        for (const auto& h : hist_)
          if (h.utime > utime - int64_t(quiet_for_ * 1e6)) rest_tail_.push_back(h);
      } else {
        rest_tail_.push_back(hist_.back());
      }
      // rest_tail_: the rest's last rest_window_s + rest_guard_s; its part older than the guard is the mean.
      while (!rest_tail_.empty() && rest_tail_.front().utime < utime - int64_t((cfg_.rest_window_s + cfg_.rest_guard_s) * 1e6))
        rest_tail_.pop_front();
      was_rest_ = true;
      return;
    }
    if (was_rest_) {
      // The rest ended: integrate from where the motion began, with the rest's own g0.
      was_rest_ = false;
      restart_from_rest();
    }
    if (std::abs(v_) > cfg_.start_speed_mps || std::abs(h_) > cfg_.start_height_m) {
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
