// Smooth sensor motion: a tripod on a dolly pushed along a C2 cubic B-spline path (closed loop or open),
// with a speed profile (ramps from and to rest, slowing in curves) tuned so the path's average and maximum
// speeds match a target, plus small roll/pitch wobble and height changes. Deterministic for a seed.
// Also: the IMU (specific force and angular rate in the sensor frame, with noise and bias).
#pragma once
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fploc/core/pose.h"

namespace fploc::sim {

struct SpeedSpec {
  double v_max = 0.55;  // m/s
  double v_avg = 0.40;  // m/s, path length / moving time
};

// Any sensor trajectory the simulator can follow (one B-spline Motion, or a Journey through a building:
// several legs on different floors, lift rides). Velocities and the IMU come from pose() by central
// differences.
class SensorTrajectory {
 public:
  virtual ~SensorTrajectory() = default;
  virtual double duration() const = 0;
  virtual double moving_time() const = 0;
  virtual double length() const = 0;      // horizontal path length [m]
  virtual double max_speed() const = 0;
  double avg_speed() const { return moving_time() > 0 ? length() / moving_time() : 0; }
  // Sensor pose (sensor frame -> world; z absolute) at time t in [0, duration()] (clamped).
  virtual Eigen::Isometry3d pose(double t) const = 0;
  // The 2D path sampled every ds metres (for clearance checks and clutter placement).
  virtual std::vector<Eigen::Vector2d> sample_path(double ds) const = 0;
  Eigen::Vector3d velocity(double t) const;
  Eigen::Vector3d acceleration(double t) const;
  Eigen::Vector3d angular_velocity_body(double t) const;
};

// The ground under the wheels: height of the wheel contact surface [m, same datum as the poses' z] at a
// plan point, `s` = the arc length of the dolly's centre along its path (a multi-floor journey uses it to
// know which floor the path is on). Empty = flat floor at z = 0.
using GroundFn = std::function<double(double s, const Eigen::Vector2d& p)>;

struct MotionConfig {
  double sensor_height_m = 1.2;
  double height_change_m = 0.04;  // amplitude of slow tripod height changes
  double wobble_deg = 0.6;        // roll/pitch wobble amplitude at full speed
  double accel_mps2 = 0.35;       // start/stop ramps
  double preroll_s = 1.0;         // standing still before the motion
  double postroll_s = 1.0;        // and after
  // Ramps and thresholds: the four wheels (wheelbase x track) follow `ground`; the dolly's z is their
  // mean and it pitches/rolls with them (pitch from front - rear, roll from left - right).
  GroundFn ground;
  double wheelbase_m = 0.5;
  double track_m = 0.45;
  double s0 = 0;                  // arc length offset of the tripod's height changes (continuity across legs)
  double t0 = 0;                  // time offset of the wobble phases (continuity across legs)
};

class Motion : public SensorTrajectory {
 public:
  // `control`: B-spline control polygon in the plan frame. When target_length > 0 the polygon is scaled
  // about its centroid so the path has that length.
  Motion(std::vector<Eigen::Vector2d> control, bool closed, SpeedSpec speed, double target_length, uint64_t seed,
         MotionConfig cfg = {});

  double duration() const override { return cfg_.preroll_s + t_move_ + cfg_.postroll_s; }
  double moving_time() const override { return t_move_; }
  double length() const override { return length_; }
  double max_speed() const override { return v_peak_; }
  bool closed() const { return closed_; }
  const std::vector<Eigen::Vector2d>& control() const { return ctrl_; }

  // Sensor pose (sensor frame -> world) at time t in [0, duration()] (clamped).
  Eigen::Isometry3d pose(double t) const override;
  // The 2D path sampled every ds metres (for clearance checks and clutter placement).
  std::vector<Eigen::Vector2d> sample_path(double ds) const override;
  // Arc length travelled at time t, and the heading of the path at arc length s.
  double s_at(double t) const { return s_at_time(t - cfg_.preroll_s, nullptr); }
  double heading_at(double s) const;
  const MotionConfig& config() const { return cfg_; }
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
  int substeps = 10;                // accelerometer: sub-intervals averaged per sample
};

// Each sample is the mean over the interval since the previous sample, (t - 1/rate, t] (a real MEMS IMU's
// anti-alias filter / delta-angle output), not the value at the instant t.
struct ImuSample {
  double t = 0;  // motion time [s]: the end of the sample's interval
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // specific force in the sensor frame [m/s^2]
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // [rad/s]
};

constexpr double kGravity = 9.80665;

// All IMU samples over the motion, at cfg.rate_hz, starting at t = 0.
std::vector<ImuSample> simulate_imu(const SensorTrajectory& m, const ImuConfig& cfg, uint64_t seed);

}  // namespace fploc::sim
