// The IMU's yaw rate for the matcher and the optimizer: a buffer of gyro z samples (sensor frame, the
// yaw rate for a level sensor) with the integral over an interval (the prediction's yaw change) and the
// mean rate over a sweep (the motion compensation's yaw rate). No transport: the nodes feed it.
#pragma once
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>

namespace fploc::matcher {

class ImuYaw {
 public:
  // Samples in time order; out-of-order, duplicate or non-finite samples are ignored (returns false).
  bool add(int64_t utime, double gyro_z);
  // Integral of the rate over (t0, t1] (trapezoid between samples, held at the ends); nullopt when the
  // samples do not cover the interval (up to `slack_us` short at its end) or two samples in it lie more than
  // max_hole_us() apart (samples lost: an IMU dropout is no constant rate).
  std::optional<double> integral(int64_t t0, int64_t t1, int64_t slack_us = 20000) const;
  // integral / (t1 - t0).
  std::optional<double> mean_rate(int64_t t0, int64_t t1, int64_t slack_us = 20000) const;
  // Forgets samples older than utime (keeps the one just before it).
  void drop_before(int64_t utime);
  size_t size() const { return s_.size(); }
  static constexpr int64_t max_hole_us() { return max_hole_us_; }

 private:
  std::deque<std::pair<int64_t, double>> s_;
  size_t max_ = 4000;
  static constexpr int64_t max_hole_us_ = 250000;
};

}  // namespace fploc::matcher