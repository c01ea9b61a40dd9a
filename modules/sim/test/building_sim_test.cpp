// The simulator in a building: ramps (z rises, the dolly pitches, the rays see the slope), door thresholds
// (a short z/pitch jolt), lift rides (the IMU feels the car's acceleration), the ground-truth floor, and
// determinism by seed. Uses the shipped demo building (data/buildings/demo-building.pbtxt).
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/core/pose.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"
#include "fploc/sim/demo_building.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using namespace fploc::sim;

namespace {

const std::string kBuilding = std::string(FPLOC_SOURCE_DIR) + "/data/buildings/demo-building.pbtxt";

SimulatorOptions opts(const std::string& scenario, uint64_t seed) {
  SimulatorOptions o;
  o.scenario = scenario;
  o.seed = seed;
  return o;
}

double pitch_of(const Eigen::Isometry3d& T) { return StampedPose::from(0, T).rpy().y(); }

}  // namespace

TEST(BuildingSim, ShippedPlansMatchCode) {
  for (const auto& f : demo_building_floors()) {
    const FloorPlan plan = demo_building_plan(f);
    const FloorPlan loaded = load_floor_plan(std::string(FPLOC_SOURCE_DIR) + "/data/buildings/demo-building/" + f + ".json");
    ASSERT_EQ(loaded.elements.size(), plan.elements.size()) << f;
    for (size_t i = 0; i < plan.elements.size(); ++i)
      EXPECT_LT((loaded.elements[i].a - plan.elements[i].a).norm() + (loaded.elements[i].c - plan.elements[i].c).norm(), 1e-9);
  }
  const Building b = load_building(kBuilding);
  ASSERT_EQ(b.floors.size(), 2u);
  EXPECT_EQ(b.connections.size(), 3u);
}

TEST(BuildingSim, RampRaisesAndPitchesTheDolly) {
  Simulator sim(load_building(kBuilding), "", opts("building-ramp-medium", 1));
  const Journey* j = sim.journey();
  ASSERT_NE(j, nullptr);
  ASSERT_EQ(j->floor_changes().size(), 1u);
  const double slope = 3.2 / 25.6;
  int on_ramp = 0;
  for (double t = 0; t < j->duration(); t += 0.25) {
    const Eigen::Isometry3d T = j->pose(t);
    const Eigen::Vector3d p = T.translation();
    if (p.y() < 17.6 || p.x() < 6 || p.x() > 27.5) continue;  // the straight part of the ramp, wheels all on it
    ++on_ramp;
    const double ground = slope * (p.x() - 4.0);
    EXPECT_NEAR(p.z() - ground, 1.2, 0.06) << "t " << t;                         // tripod height above the ramp
    EXPECT_NEAR(pitch_of(T), -std::atan(slope), 1.2 * M_PI / 180) << "t " << t;  // nose up, +- wobble and tilt
    EXPECT_EQ(sim.floor_at(sim.options().t0_s + t), p.x() < 16.8 ? 0 : 1) << "x " << p.x();
  }
  EXPECT_GT(on_ramp, 100);
  // The end: on the first floor, 1.2 m above it.
  const Eigen::Vector3d end = j->pose(j->duration()).translation();
  EXPECT_NEAR(end.z(), 3.2 + 1.2, 0.06);
  EXPECT_EQ(sim.floor_at(sim.options().t0_s + j->duration()), 1);
  // The lidar sees the slope: rays straight down from half-way up the ramp end on the ramp (floor label).
  const World& w = *sim.floor_worlds_for_test(0);
  const Hit h = w.cast(Eigen::Vector3d(12, 18.75, 2.5), Eigen::Vector3d(0, 0, -1), 50);
  EXPECT_EQ(h.label, Label::kFloor);
  EXPECT_NEAR(h.t, 2.5 - slope * 8, 1e-6);
  // And from the first floor's world, the ramp goes down below its floor.
  const World& w1 = *sim.floor_worlds_for_test(1);
  const Hit h1 = w1.cast(Eigen::Vector3d(20, 18.75, 1.0), Eigen::Vector3d(0, 0, -1), 50);
  EXPECT_EQ(h1.label, Label::kFloor);
  EXPECT_NEAR(h1.t, 1.0 - (slope * 16 - 3.2), 1e-6);
}

TEST(BuildingSim, ThresholdsJoltTheDolly) {
  Simulator sim(load_building(kBuilding), "", opts("building-thresholds-medium", 2));
  const Journey* j = sim.journey();
  ASSERT_NE(j, nullptr);
  // Crossing the doorway in x = 24 (y 2.5-3.5) and x = 14 (y 8-9): z and pitch jolt, elsewhere smooth.
  for (double xd : {24.0, 14.0}) {
    double zmax = -1e9, zmin = 1e9, pmax = -1e9, pmin = 1e9, zfar = 0;
    int nfar = 0;
    for (double t = 0; t < j->duration(); t += 0.002) {
      const Eigen::Isometry3d T = j->pose(t);
      const double dx = std::abs(T.translation().x() - xd);
      if (dx < 0.5) {
        zmax = std::max(zmax, T.translation().z());
        zmin = std::min(zmin, T.translation().z());
        pmax = std::max(pmax, pitch_of(T));
        pmin = std::min(pmin, pitch_of(T));
      } else if (dx < 1.2) {
        zfar += T.translation().z();
        ++nfar;
      }
    }
    ASSERT_GT(nfar, 0);
    // Front wheels up (nose up: pitch < 0), then the rear: a jolt of about atan(h / wheelbase) each way.
    EXPECT_GT(zmax - zmin, 0.008) << xd;
    EXPECT_LT(zmax - zmin, 0.04 + 0.01) << xd;
    EXPECT_GT(pmax - pmin, 2 * std::atan(0.015 / 0.5)) << xd;
    EXPECT_LT(pmax - pmin, 2 * std::atan(0.035 / 0.5) + 0.03) << xd;
  }
  // The thresholds are in the world: a ray down onto a doorway's threshold ends 2-3 cm higher.
  const World& w = *sim.floor_worlds_for_test(0);
  const Hit on = w.cast(Eigen::Vector3d(24, 3, 1.0), Eigen::Vector3d(0, 0, -1), 5);
  const Hit off = w.cast(Eigen::Vector3d(23.5, 3, 1.0), Eigen::Vector3d(0, 0, -1), 5);
  EXPECT_EQ(on.label, Label::kFloor);
  EXPECT_GT(off.t - on.t, 0.019);
  EXPECT_LT(off.t - on.t, 0.031);
}

TEST(BuildingSim, LiftRideIsSeenByTheImu) {
  Simulator sim(load_building(kBuilding), "", opts("building-twofloor-fast", 3));
  const Journey* j = sim.journey();
  ASSERT_NE(j, nullptr);
  const auto& ch = j->floor_changes();
  ASSERT_EQ(ch.size(), 2u);
  EXPECT_EQ(ch[0].how, "ramp ramp");
  EXPECT_EQ(ch[1].how, "lift lift");
  EXPECT_EQ(ch[1].from, 1);
  EXPECT_EQ(ch[1].to, 0);
  const LiftProfile prof(-3.2, LiftConfig{});
  const double t_end = ch[1].t, t_start = t_end - prof.duration();
  EXPECT_GT(prof.duration(), 3.0);
  EXPECT_LT(prof.duration(), 10.0);
  // Vertical specific force in the world frame (the dolly stands still with a small static tilt).
  double fmin = 1e9, fmax = -1e9, still = 0;
  for (const auto& s : sim.imu()) {
    const Eigen::Vector3d f = j->pose(s.t).linear() * s.accel;
    if (s.t > t_start && s.t < t_end) {
      fmin = std::min(fmin, f.z());
      fmax = std::max(fmax, f.z());
    } else if (s.t > t_start - 2.5 && s.t < t_start - 0.5) {
      still = std::max(still, std::abs(f.z() - kGravity));
    }
  }
  // Going down: first lighter (the car accelerates downwards), then heavier (it brakes).
  EXPECT_LT(fmin, kGravity - 0.6);
  EXPECT_GT(fmax, kGravity + 0.6);
  EXPECT_GT(fmin, kGravity - 1.0);
  EXPECT_LT(fmax, kGravity + 1.0);
  EXPECT_LT(still, 0.25);  // standing in the car before: gravity + noise + bias only
  // The car moves the sensor down by the floors' difference; the ground-truth floor switches on arrival.
  EXPECT_NEAR(j->pose(t_start - 0.1).translation().z() - j->pose(t_end + 0.1).translation().z(), 3.2, 1e-3);
  const double t0 = sim.options().t0_s;
  EXPECT_EQ(sim.floor_at(t0 + t_end - 0.2), 1);
  EXPECT_EQ(sim.floor_at(t0 + t_end + 0.2), 0);
  EXPECT_EQ(sim.state_at(t0 + t_start + 1), "lift-moving");
  // Doors closed: the scan sees only the car (every return within its 2.4 x 2.4 x 2.4 m box).
  const int k = int((t_start + 1.0) * sim.options().rate_hz);
  SimScan f;
  sim.frame(k, f);
  int returns = 0;
  for (size_t i = 0; i < f.true_range_m.size(); ++i) {
    if (f.true_range_m[i] <= 0) continue;
    ++returns;
    EXPECT_LT(f.true_range_m[i], 3.5);
  }
  EXPECT_GT(returns, 30000);
  // Its ground truth is absolute: between the two floors.
  EXPECT_GT(f.gt.p.z(), 1.2);
  EXPECT_LT(f.gt.p.z(), 3.2 + 1.3);
}

TEST(BuildingSim, DeterministicBySeed) {
  const Building b = load_building(kBuilding);
  Simulator a(b, "", opts("building-twofloor-fast", 5)), c(b, "", opts("building-twofloor-fast", 5)),
      d(b, "", opts("building-twofloor-fast", 6));
  ASSERT_EQ(a.imu().size(), c.imu().size());
  for (size_t i = 0; i < a.imu().size(); i += 97) EXPECT_EQ(a.imu()[i].accel, c.imu()[i].accel);
  SimScan fa, fc, fd;
  const int k = a.num_frames() / 3;
  a.frame(k, fa);
  c.frame(k, fc);
  d.frame(k, fd);
  EXPECT_EQ(fa.scan.range_mm, fc.scan.range_mm);
  EXPECT_NE(fa.scan.range_mm, fd.scan.range_mm);
  EXPECT_EQ(a.info(), c.info());
}

TEST(BuildingSim, AutoLoopOnABuildingFloor) {
  // auto-loop keeps to one floor (ramps, stairs and the lift are walls for the planner); poses absolute.
  Simulator sim(load_building(kBuilding), "first", opts("auto-loop-fast", 1));
  EXPECT_EQ(sim.journey(), nullptr);
  EXPECT_GT(sim.num_frames(), 100);
  for (double t = 0; t < sim.motion().duration(); t += 1.0) {
    const Eigen::Vector3d p = sim.motion().pose(t).translation();
    EXPECT_NEAR(p.z(), 3.2 + 1.2, 0.07);
    EXPECT_FALSE(p.y() > 17.5 && p.x() > 4 && p.x() < 29.6) << "on the ramp at t " << t << ": " << p.transpose();
  }
  EXPECT_EQ(sim.floor_at(sim.options().t0_s + 5), 1);
  EXPECT_THROW(Simulator(load_building(kBuilding), "roof", opts("auto-loop-fast", 1)), std::runtime_error);
  // A journey needs the building.
  EXPECT_THROW(Simulator(demo_building_plan("ground"), opts("building-twofloor-medium", 1)), std::runtime_error);
}
