// Smooth sensor motion: a tripod on a dolly pushed along a C2 cubic B-spline path (closed loop or open),
// with a speed profile (ramps from and to rest, slowing in curves) tuned so the path's average and maximum
// speeds match a target, plus small roll/pitch wobble and height changes. Deterministic for a seed.
// Also: the IMU (specific force and angular rate in the sensor frame, with noise and bias).
#pragma once
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/core/pose.h"

namespace fploc::sim {

struct SpeedSpec {
  double v_max = 0.55;  // m/s
  double v_avg = 0.40;  // m/s, path length / moving time
};

struct MotionConfig {
  double sensor_height_m = 1.2;
  double height_change_m = 0.04;  // amplitude of slow tripod height changes
  double wobble_deg = 0.6;        // roll/pitch wobble amplitude at full speed
  double accel_mps2 = 0.35;       // start/stop ramps
  double preroll_s = 1.0;         // standing still before the motion
  double postroll_s = 1.0;        // and after
};

class Motion {
 public:
  // `control`: B-spline control polygon in the plan frame. When target_length > 0 the polygon is scaled
  // about its centroid so the path has that length.
  Motion(std::vector<Eigen::Vector2d> control, bool closed, SpeedSpec speed, double target_length, uint64_t seed,
         MotionConfig cfg = {});

  double duration() const { return cfg_.preroll_s + t_move_ + cfg_.postroll_s; }
  double moving_time() const { return t_move_; }
  double length() const { return length_; }
  double max_speed() const { return v_peak_; }
  double avg_speed() const { return t_move_ > 0 ? length_ / t_move_ : 0; }
  bool closed() const { return closed_; }
  const std::vector<Eigen::Vector2d>& control() const { return ctrl_; }

  // Sensor pose (sensor frame -> world) at time t in [0, duration()] (clamped).
  Eigen::Isometry3d pose(double t) const;
  // Derivatives by central differences of pose(): world velocity/acceleration, body angular velocity.
  Eigen::Vector3d velocity(double t) const;
  Eigen::Vector3d acceleration(double t) const;
  Eigen::Vector3d angular_velocity_body(double t) const;
  // The 2D path sampled every ds metres (for clearance checks and clutter placement).
  std::vector<Eigen::Vector2d> sample_path(double ds) const;
  // Path point / heading at arc length s.
  Eigen::Vector2d point_at(double s) const;
  double speed_at_s(double s) const;

 private:
  Eigen::Vector2d spline(double u) const;
  Eigen::Vector2d spline_d(double u) const;
  double u_at(double s) const;
  double s_at_time(double tm, double* v) const;

  std::vector<Eigen::Vector2d> ctrl_;
  bool closed_;
  SpeedSpec speed_;
  MotionConfig cfg_;
  int nseg_ = 0;
  std::vector<double> tab_u_, tab_s_;  // arc-length table
  std::vector<double> prof_v_;         // speed at tab_s_
  double ds_prof_ = 0.02;
  double length_ = 0;
  std::vector<double> time_s_, time_v_;  // s(t), v(t) every dt_
  double dt_ = 0.01;
  double t_move_ = 0;
  double v_peak_ = 0;
  // Wobble parameters.
  double ph_[8] = {0};
  double roll0_ = 0, pitch0_ = 0;
};

struct ImuConfig {
  double rate_hz = 200;
  double accel_noise = 0.015;       // m/s^2 white noise per sample
  double gyro_noise = 0.0015;       // rad/s
  double accel_bias_sigma = 0.04;   // constant bias drawn per run
  double gyro_bias_sigma = 0.002;
  double accel_bias_walk = 0.0005;  // random walk per sqrt(s)
  double gyro_bias_walk = 0.00005;
};

struct ImuSample {
  double t = 0;  // motion time [s]
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // specific force in the sensor frame [m/s^2]
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // [rad/s]
};

constexpr double kGravity = 9.80665;

// All IMU samples over the motion, at cfg.rate_hz, starting at t = 0.
std::vector<ImuSample> simulate_imu(const Motion& m, const ImuConfig& cfg, uint64_t seed);

}  // namespace fploc::sim
