// Odometry inputs of the AMCL baseline (no LCM).
//  - WheelOdometrySim: what a wheeled robot's odometry would report, made from the simulator's ground
//    truth: each increment between two ground-truth poses (in the previous pose's frame) is corrupted by a
//    systematic scale error (wheel radius), a systematic yaw drift per metre (wheel base / unequal wheels)
//    and white noise whose variance grows with the distance (random walk), then integrated. Seeded.
//  - OdometryGuard: rejects non-finite poses and jumps (a step between consecutive odometry poses larger
//    than a limit); a rejected step is treated as "no motion" by re-anchoring the odometry frame, so the
//    filter and the published pose never jump with it.
#pragma once
#include <cstdint>
#include <string>

#include "fploc/core/rng.h"
#include "fploc/core/pose.h"

namespace fploc::amcl {

struct WheelOdometryConfig {
  double scale_error = 0.02;            // travelled distance reported (1 + scale_error) times too long
  double yaw_drift_deg_per_m = 1.0;     // systematic heading error per metre travelled
  double trans_noise_m_per_sqrt_m = 0.01;   // white noise along and across the motion, std after 1 m
  double yaw_noise_deg_per_sqrt_m = 0.5;    // white heading noise, std after 1 m
  uint64_t seed = 2;
};

class WheelOdometrySim {
 public:
  explicit WheelOdometrySim(WheelOdometryConfig c = {});
  // Start pose of the odometry frame (default: origin).
  void set_start(const Pose2& p) { start_ = p; }
  // Next ground-truth pose (plan frame) -> odometry pose (odometry frame). The first call returns the start.
  Pose2 update(const Pose2& truth);
  double distance() const { return distance_; }

 private:
  WheelOdometryConfig c_;
  PolarRng rng_;
  bool have_ = false;
  Pose2 start_, last_truth_, odom_;
  double distance_ = 0;
};

struct OdometryGuardConfig {
  double max_step_m = 1.0;       // between two consecutive odometry poses
  double max_step_rad = 0.7854;  // 45 deg
};

class OdometryGuard {
 public:
  explicit OdometryGuard(OdometryGuardConfig c = {}) : c_(c) {}
  // Raw odometry pose -> corrected pose (continuous). Returns false (and *problem) for a non-finite pose
  // (then *out is not set); a jump is reported in *problem but the call returns true with the jump removed.
  bool correct(const Pose2& raw, Pose2* out, std::string* problem);
  int jumps() const { return jumps_; }

 private:
  OdometryGuardConfig c_;
  bool have_ = false;
  Pose2 last_raw_;
  Pose2 fix_;  // corrected = fix_ * raw
  int jumps_ = 0;
};

}  // namespace fploc::amcl
