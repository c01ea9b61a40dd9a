// Scenario trajectories: lengths and speeds against the paper, clearance, IMU consistent with the motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fploc/sim/planner.h"
#include "fploc/sim/scenarios.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using namespace fploc::sim;

TEST(Motion, ScenariosMatchPaperLengthsAndSpeeds) {
  for (const auto& name : scenario_names()) {
    ScenarioSpec spec;
    ASSERT_TRUE(scenario_spec(name, spec, nullptr));
    if (spec.plan_kind == "any" || spec.plan_kind == "building") continue;  // building journeys: building_sim_test
    const FloorPlan plan = spec.plan_kind == "room" ? demo_room_plan() : demo_corridor_plan();
    const Motion m(spec.control, spec.closed, spec.speed, spec.length, 1);
    // Measure from sampled poses (independent of the internal tables).
    const double dt = 0.01;
    double len = 0, vmax = 0, t_first = -1, t_last = 0;
    Eigen::Vector3d prev = m.pose(0).translation();
    for (double t = dt; t <= m.duration() + 1e-9; t += dt) {
      const Eigen::Vector3d p = m.pose(t).translation();
      const double d = (p - prev).head<2>().norm();
      len += d;
      const double v = d / dt;
      vmax = std::max(vmax, v);
      if (v > 0.005) {
        if (t_first < 0) t_first = t - dt;
        t_last = t;
      }
      prev = p;
    }
    const double vavg = len / (t_last - t_first);
    EXPECT_NEAR(len, spec.length, 0.01 * spec.length) << name;
    EXPECT_NEAR(vavg, spec.speed.v_avg, 0.03 * spec.speed.v_avg) << name;
    EXPECT_NEAR(vmax, spec.speed.v_max, 0.03 * spec.speed.v_max) << name;
    if (spec.closed) EXPECT_LT((m.pose(m.duration()).translation() - m.pose(0).translation()).head<2>().norm(), 0.01) << name;
    EXPECT_GE(min_clearance(plan, m.sample_path(0.05)), 0.4) << name;
  }
}

TEST(Motion, TripodWobbleAndHeight) {
  ScenarioSpec spec;
  ASSERT_TRUE(scenario_spec("room-large-loop-fast", spec, nullptr));
  const Motion m(spec.control, spec.closed, spec.speed, spec.length, 5);
  double zmin = 1e9, zmax = -1e9, tilt_max = 0;
  for (double t = 0; t < m.duration(); t += 0.05) {
    const StampedPose p = StampedPose::from(t, m.pose(t));
    zmin = std::min(zmin, p.p.z());
    zmax = std::max(zmax, p.p.z());
    const Eigen::Vector3d rpy = p.rpy();
    tilt_max = std::max({tilt_max, std::abs(rpy.x()), std::abs(rpy.y())});
  }
  EXPECT_GT(zmax - zmin, 0.02);
  EXPECT_LT(zmax - zmin, 0.2);
  EXPECT_GT(tilt_max, 0.1 * M_PI / 180);
  EXPECT_LT(tilt_max, 2.0 * M_PI / 180);
}

TEST(Motion, ImuIntegratesToTrajectory) {
  ScenarioSpec spec;
  ASSERT_TRUE(scenario_spec("room-small-loop-fast", spec, nullptr));
  const Motion m(spec.control, spec.closed, spec.speed, spec.length, 2);
  ImuConfig ic;
  ic.rate_hz = 200;
  ic.accel_noise = ic.gyro_noise = ic.accel_bias_sigma = ic.gyro_bias_sigma = ic.accel_bias_walk = ic.gyro_bias_walk = 0;
  const auto imu = simulate_imu(m, ic, 2);
  ASSERT_GT(imu.size(), 1000u);
  // Standing still: specific force is gravity in the sensor frame.
  EXPECT_NEAR(imu[10].accel.norm(), kGravity, 0.01);
  // Strapdown integration over 5 s windows from the true state.
  const double dt = 1.0 / ic.rate_hz;
  for (double t0 : {5.0, 20.0, 35.0}) {
    Eigen::Quaterniond q(m.pose(t0).linear());
    Eigen::Vector3d p = m.pose(t0).translation(), v = m.velocity(t0);
    size_t k = size_t(std::llround(t0 / dt));
    const size_t k1 = k + size_t(5.0 / dt);
    for (; k < k1; ++k) {
      const auto& a = imu[k];
      const auto& b = imu[k + 1];
      const Eigen::Vector3d w = b.gyro;  // the mean rate over (t_k, t_k+1]
      const Eigen::Quaterniond q1 = q * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm() * dt, w.norm() > 0 ? w.normalized() : Eigen::Vector3d::UnitZ()));
      const Eigen::Vector3d acc = 0.5 * (q * a.accel + q1 * b.accel) - Eigen::Vector3d(0, 0, kGravity);
      p += v * dt + 0.5 * acc * dt * dt;
      v += acc * dt;
      q = q1;
    }
    const Eigen::Isometry3d T = m.pose(k1 * dt);
    EXPECT_LT((p - T.translation()).norm(), 0.05) << "t0 " << t0;
    EXPECT_LT(Eigen::AngleAxisd(q.inverse() * Eigen::Quaterniond(T.linear())).angle(), 0.2 * M_PI / 180) << "t0 " << t0;
  }
}

// A door threshold's jolt: the sensor pitches 2.9 deg and back within 50 ms (a wheel climbing a 2.5 cm edge),
// rising 1.25 cm. An IMU at 100 Hz outputs the mean over each sample's interval (a real MEMS IMU's band-limited
// output), so the sum of its samples is exact: the rotation and velocity change over the jolt are kept, not
// aliased (point samples at 100 Hz see two or three values of a 50 ms spike).
namespace {
struct Jolt : SensorTrajectory {
  double duration() const override { return 2.0; }
  double moving_time() const override { return 0; }
  double length() const override { return 0; }
  double max_speed() const override { return 0; }
  std::vector<Eigen::Vector2d> sample_path(double) const override { return {}; }
  Eigen::Isometry3d pose(double t) const override {
    // A sharp rise (square root: the wheel touching the edge) at t = 1.003 s, 50 ms up, then stays.
    const double s = std::clamp((t - 1.003) / 0.05, 0.0, 1.0);
    const double f = std::sqrt(s);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(-2.9 * M_PI / 180 * f, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(0, 0, 1.2 + 0.0125 * f);
    return T;
  }
};
}  // namespace

TEST(Motion, ImuSamplesAreIntervalMeansSoAJoltIsNotAliased) {
  const Jolt m;
  ImuConfig ic;
  ic.rate_hz = 100;
  ic.accel_noise = ic.gyro_noise = ic.accel_bias_sigma = ic.gyro_bias_sigma = ic.accel_bias_walk = ic.gyro_bias_walk = 0;
  const auto imu = simulate_imu(m, ic, 1);
  double pitch = 0, vz = 0;
  for (size_t k = 1; k < imu.size(); ++k) {
    pitch += imu[k].gyro.y() * 0.01;
    vz += (imu[k].accel.z() - kGravity * std::cos(pitch)) * 0.01;
  }
  // The jolt's net rotation (2.9 deg) to within 0.01 deg; its vertical velocity change (0) to 1 mm/s.
  EXPECT_NEAR(pitch, -2.9 * M_PI / 180, 0.01 * M_PI / 180);
  EXPECT_NEAR(vz, 0.0, 0.002);
  // The samples inside the jolt carry its mean rate (-2.9 deg over 50 ms ~ -1 rad/s), not the value at an instant.
  double peak = 0;
  for (const auto& s : imu) peak = std::min(peak, s.gyro.y());
  EXPECT_LT(peak, -0.5);
  EXPECT_GT(peak, -3.0);
}
