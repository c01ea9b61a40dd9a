// FloorTracker and VerticalImu on synthetic inputs: a lift ride (IMU specific force with bias and noise),
// a ramp (the IMU's tilt, or the segmenter's z), rides that must not switch.
#include "fploc/localizer/floor_tracker.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

using namespace fploc;
using namespace fploc::localizer;

namespace {

constexpr double kG = 9.80665;

std::shared_ptr<Building> two_floors() {
  auto b = std::make_shared<Building>();
  b->source = "synthetic";
  BuildingFloor g, f;
  g.name = "ground";
  g.elevation = 0;
  f.name = "first";
  f.elevation = 3.3;
  b->floors = {g, f};
  FloorConnection ramp;
  ramp.name = "ramp";
  ramp.kind = ConnectionKind::kRamp;
  ramp.from_floor = "ground";
  ramp.to_floor = "first";
  ramp.polygon = {{10, 0}, {10, 2}, {20, 2}, {20, 0}};  // foot edge v0-v1 at x = 10, head v2-v3 at x = 20
  FloorConnection lift;
  lift.name = "lift";
  lift.kind = ConnectionKind::kLift;
  lift.from_floor = "ground";
  lift.to_floor = "first";
  lift.polygon = {{0, 5}, {2, 5}, {2, 7}, {0, 7}};
  b->connections = {ramp, lift};
  return b;
}

// Specific force of a sensor with roll/pitch (levelled frame: gravity only) plus vertical acceleration a,
// a constant bias and white noise.
struct ImuGen {
  std::mt19937 rng{7};
  std::normal_distribution<double> n{0, 0.015};
  Eigen::Vector3d bias{0.04, -0.03, 0.05};
  Eigen::Vector3d operator()(double roll, double pitch, double a_up) {
    const double g = kG + a_up;
    const Eigen::Vector3d f(-std::sin(pitch) * g, std::cos(pitch) * std::sin(roll) * g, std::cos(pitch) * std::cos(roll) * g);
    return f + bias + Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
};

// A lift ride profile: rest, accelerate (a for ta s), cruise (tc s), brake, rest. Returns the height.
double ride_accel(double t, double a, double ta, double tc, double t0) {
  const double s = t - t0;
  if (s < 0) return 0;
  if (s < ta) return a;
  if (s < ta + tc) return 0;
  if (s < 2 * ta + tc) return -a;
  return 0;
}

struct LiftRun {
  std::optional<FloorSwitch> sw;
  double switch_t = -1;
  double arrive_t = 0;
  double z_before_arrival = 0;  // pose_z() 0.5 s before the arrival (riding)
  double z_sigma_mid = 0;       // pose_z_sigma(0.01) mid-ride
  double z_after = 0;           // pose_z() at the end
};

// Runs a ride of `height` (a = 0.5 m/s^2, 2 s ramps) starting at t = 3 s with the robot standing at p,
// frames every 0.1 s, IMU at 200 Hz.
// The segmenter's z: 1.2 m, or seg_z(t); times from start_us on.
LiftRun run_ride(FloorTracker& tr, const Eigen::Vector2d& p, double height, double duration = 15,
                 const std::function<double(double)>& seg_z = nullptr, int64_t start_us = 0) {
  ImuGen imu;
  const double a = 0.5 * (height > 0 ? 1 : -1), ta = 2.0;
  const double tc = std::max(0.0, (std::abs(height) - 0.5 * ta * ta) / (0.5 * ta));  // ramps: 1 m each
  LiftRun r;
  r.arrive_t = 3 + 2 * ta + tc;
  int64_t frame_us = 0;
  for (int64_t us = 0; us < int64_t(duration * 1e6); us += 5000) {
    const double t = us * 1e-6;
    tr.add_imu(start_us + us, imu(0.002, -0.003, ride_accel(t, a, ta, tc, 3.0)));
    if (us >= frame_us) {
      frame_us += 100000;
      FloorObservation o;
      o.utime = start_us + us;
      o.pose = {p.x(), p.y(), 0.3};
      o.inlier_ratio = t > 3 && t < r.arrive_t ? 0.3 : 0.9;
      o.z = seg_z ? seg_z(t) : 1.2;
      o.z_known = true;
      if (auto s = tr.update(o); s && !r.sw) r.sw = s, r.switch_t = t;
      if (std::abs(t - (r.arrive_t - 0.5)) < 0.05) r.z_before_arrival = tr.pose_z();
      if (std::abs(t - 0.5 * (3 + r.arrive_t)) < 0.05) r.z_sigma_mid = tr.pose_z_sigma(0.01);
      r.z_after = tr.pose_z();
    }
  }
  return r;
}

}  // namespace

TEST(VerticalImu, RideHeightWithBiasAndNoise) {
  VerticalImu v;
  ImuGen imu;
  std::optional<VerticalRide> ride;
  for (int64_t us = 0; us < 15'000'000; us += 5000) {
    v.add(us, imu(0.01, 0.02, ride_accel(us * 1e-6, 0.5, 2.0, 2.6, 3.0)));
    if (auto r = v.take_ride()) ride = r;
  }
  ASSERT_TRUE(ride);
  EXPECT_NEAR(ride->height_m, 2.0 + 2.6, 0.05);
  EXPECT_NEAR(ride->peak_speed_mps, 1.0, 0.05);
  EXPECT_NEAR(ride->start_utime * 1e-6, 3.45, 0.3);
  EXPECT_LT(ride->end_utime * 1e-6, 3 + 4 + 2.6 + 1.0);  // at rest within a second of the stop
}

// The demo building's lift after driving in: |f| while driving is larger than g by a_h^2 / 2g and wobbles,
// so the running mean of |f| is off by ~0.01 m/s^2 when the robot stops; it stands 3 s with the doors
// closing, then a jerk-limited ride (a = 0.8 sin^2, 3.2 m down) whose first 0.2 s stay below the quiet
// threshold. The ride's height must come out within 1.5 cm (the rest's own |f| as g0, the integration from
// where the motion began), where the running mean and the late start lost ~10 cm (3 %).
TEST(VerticalImu, RideAfterDrivingInUsesTheRestAndItsStart) {
  VerticalImu v;
  ImuGen imu;
  std::optional<VerticalRide> ride;
  const double ta = 2.5, tc = 0.7, A = 0.8, t0 = 13.0;  // the simulator's LiftProfile for 3.2 m (v 1 m/s)
  auto a_up = [&](double s) {
    if (s <= 0 || s >= 2 * ta + tc) return 0.0;
    if (s < ta) return -A * std::pow(std::sin(M_PI * s / ta), 2);
    if (s < ta + tc) return 0.0;
    return A * std::pow(std::sin(M_PI * (2 * ta + tc - s) / ta), 2);
  };
  double h_true = 0, v_true = 0;
  for (int64_t us = 0; us < 25'000'000; us += 10000) {
    const double t = us * 1e-6;
    Eigen::Vector3d f = imu(0.01, 0.02, a_up(t - t0));
    if (t < 10.0) {
      // Driving: horizontal accelerations of 0.4 m/s^2 (turning, speeding up) and a vertical wobble.
      f.x() += 0.4 * std::cos(0.7 * t);
      f.y() += 0.4 * std::sin(0.9 * t);
      f.z() += 0.03 * std::sin(7.0 * t);
    }
    v.add(us, f);
    if (t > t0) {
      v_true += a_up(t - t0) * 0.01;
      h_true += v_true * 0.01;
    }
    if (auto r = v.take_ride()) ride = r;
  }
  ASSERT_TRUE(ride);
  EXPECT_NEAR(h_true, -3.2, 0.01);
  EXPECT_NEAR(ride->height_m, -3.2, 0.015);
}

TEST(VerticalImu, StandingStillIsNoRide) {
  VerticalImu v;
  ImuGen imu;
  for (int64_t us = 0; us < 30'000'000; us += 5000) {
    v.add(us, imu(0.01, 0.02, 0));
    EXPECT_FALSE(v.take_ride());
    EXPECT_FALSE(v.riding());
  }
}

TEST(FloorTracker, LiftUpSwitchesAfterArrivalAndSaysWhy) {
  FloorTracker tr(two_floors(), 0);
  const LiftRun r = run_ride(tr, {1, 6}, 3.3);
  ASSERT_TRUE(r.sw);
  EXPECT_EQ(r.sw->from, 0);
  EXPECT_EQ(r.sw->to, 1);
  EXPECT_EQ(r.sw->to_name, "first");
  EXPECT_EQ(r.sw->via.name, "lift");
  EXPECT_NEAR(r.z_before_arrival, 1.2 + 3.3 - 0.0625, 0.1);  // 0.5 s before the stop: 6.25 cm to go
  EXPECT_GT(r.z_sigma_mid, 0.02);                              // grown while integrating the IMU
  EXPECT_NEAR(r.z_after, 3.3 + 1.2, 1e-9);                    // absolute: the new floor + the segmenter's z
  EXPECT_NE(tr.status_text().find("z 4."), std::string::npos) << tr.status_text();  // the snap is said
  EXPECT_GT(r.switch_t, r.arrive_t);
  EXPECT_LT(r.switch_t, r.arrive_t + 2.0);
  EXPECT_NE(r.sw->reason.find("lift 'lift': IMU vertical motion +3.3"), std::string::npos) << r.sw->reason;
  EXPECT_NE(r.sw->reason.find("the plan of 'ground' matched"), std::string::npos) << r.sw->reason;
  EXPECT_EQ(tr.floor(), 1);
  EXPECT_EQ(tr.floor_name(), "first");
  EXPECT_NE(tr.status_text().find("'ground' -> 'first'"), std::string::npos);
  // The search disc holds the lift's polygon.
  EXPECT_NEAR(r.sw->search_center.x(), 1, 1e-9);
  EXPECT_NEAR(r.sw->search_center.y(), 6, 1e-9);
  EXPECT_GE(r.sw->search_radius_m, std::sqrt(2.0));
}

TEST(FloorTracker, LiftDown) {
  FloorTracker tr(two_floors(), 1);
  const LiftRun r = run_ride(tr, {1.5, 5.5}, -3.3);
  ASSERT_TRUE(r.sw);
  EXPECT_EQ(r.sw->to, 0);
  EXPECT_EQ(tr.floor_name(), "ground");
}

// The robot drives to the lift at 1.20 m (the nominal height it learns), stands in the car at 1.23 m (the last
// 3 s before the ride), rides 3.3 m up; after arriving the segmenter sees only the car (a ceiling it has not
// learned: its z 20 cm off, gated). The pose's z is the new floor's level + the height the sensor stood at in
// the car, carried through the ride (the car moved, not the sensor in it), not the nominal 1.20 m.
TEST(FloorTracker, AfterARideAGatedZKeepsTheHeightTheSensorStoodAtInTheCar) {
  FloorTracker tr(two_floors(), 0);
  for (int k = 0; k < 40; ++k) {  // driving to the lift
    FloorObservation o;
    o.utime = int64_t(k) * 100000;
    o.pose = {5 + 0.05 * k, 10, 0};
    o.z = 1.2;
    o.z_known = true;
    tr.update(o);
  }
  ASSERT_NEAR(tr.nominal_z().value_or(0), 1.2, 1e-9);
  const double arrive = 3 + 2 * 2.0 + (3.3 - 2.0) / 1.0;  // run_ride's profile: 2 s ramps, 1 m/s cruise
  double z_gated = 0;
  std::string src;
  const LiftRun r = run_ride(tr, {1, 6}, 3.3, 12, [&](double t) {
    if (t > arrive + 1.5 && z_gated == 0) z_gated = tr.pose_z(), src = tr.z_source();
    return t > arrive ? 1.43 : 1.23;
  }, 4'000'000);
  ASSERT_NEAR(r.arrive_t, arrive, 1e-9);
  ASSERT_TRUE(r.sw);
  EXPECT_EQ(tr.floor(), 1);
  EXPECT_NEAR(z_gated, 3.3 + 1.23, 1e-6) << src;
  EXPECT_NE(src.find("last good height 1.23 m"), std::string::npos) << src;
}

TEST(FloorTracker, RideOutsideALiftOrToNoFloorDoesNotSwitch) {
  {
    FloorTracker tr(two_floors(), 0);
    EXPECT_FALSE(run_ride(tr, {6, 6}, 3.3).sw);  // not in the lift area
    EXPECT_EQ(tr.floor(), 0);
  }
  {
    FloorTracker tr(two_floors(), 0);
    EXPECT_FALSE(run_ride(tr, {1, 6}, 1.7).sw);  // half a floor: no floor there
    EXPECT_EQ(tr.floor(), 0);
    EXPECT_NE(tr.status_text().find("matches no floor"), std::string::npos) << tr.status_text();
  }
  {
    FloorTracker tr(two_floors(), 0);
    EXPECT_FALSE(run_ride(tr, {1, 6}, -3.3).sw);  // no floor below the ground floor
    EXPECT_EQ(tr.floor(), 0);
  }
}

namespace {

// Drives along y = 1 from x = 0 to x = 30 at 0.5 m/s; the ramp rises 3.3 m between x = 10 and 20. With
// `imu` the tilt comes from the IMU (the segmenter's z stays at the ground plane's 1.2 m, as over a
// ramp), else the segmenter's z follows the climb. Returns the x of the switch (or -1).
double drive_ramp(FloorTracker& tr, bool imu, bool relearn_z) {
  ImuGen gen;
  const double slope = 3.3 / 10, pitch = -std::atan(slope);
  double switch_x = -1;
  int64_t frame_us = 0;
  for (int64_t us = 0; us < 60'000'000; us += 5000) {
    const double t = us * 1e-6, x = 0.5 * t;
    const bool on_ramp = x > 10 && x < 20;
    if (imu) tr.add_imu(us, gen(0.003 * std::sin(t), (on_ramp ? pitch : 0) + 0.005 * std::sin(1.3 * t), 0));
    if (us < frame_us) continue;
    frame_us += 100000;
    const double climb = std::clamp((x - 10) * slope, 0.0, 3.3);
    FloorObservation o;
    o.utime = us;
    o.pose = {x, 1, 0};
    o.z_known = true;
    // From the ramp's own plane (IMU case): the distance across the plane, 1.2 m vertically above it.
    o.z = imu ? (x >= 10 && x <= 20 ? 1.2 * std::cos(std::atan(slope)) : 1.2) : 1.2 + climb;
    if (!imu && relearn_z && x > 24) o.z = 1.2;  // the segmenter re-learned its ceiling on the new floor
    if (auto s = tr.update(o)) {
      EXPECT_EQ(switch_x, -1) << "switched twice: " << s->reason;
      switch_x = x;
      EXPECT_EQ(s->via.name, "ramp");
      EXPECT_NE(s->reason.find(imu ? "IMU tilt" : "z +1."), std::string::npos) << s->reason;
    }
    if (x > 22) EXPECT_NEAR(tr.floor_z(o.z), 1.2, 0.05) << "x " << x;
    // The pose's absolute z follows the climb continuously, through the switch (the ramp's geometry
    // tells which reference the segmenter's z has).
    // (5 cm: on this steep ramp, 18 deg, near its ends the segmenter's z above the surface and above a
    // floor's level differ by less than z0 (1/cos - 1) = 6 cm: either reading is near.)
    if (std::abs(x - 10) > 0.01 && std::abs(x - 20) > 0.01)  // (on the polygon's edges: either side)
      EXPECT_NEAR(tr.pose_z(), 1.2 + climb, 0.05) << "x " << x << " (" << tr.z_source() << ")";
  }
  return switch_x;
}

}  // namespace

TEST(FloorTracker, RampUpFromTheImuTilt) {
  FloorTracker tr(two_floors(), 0);
  const double x = drive_ramp(tr, true, false);
  EXPECT_GT(x, 14.5);
  EXPECT_LT(x, 16.5);
  EXPECT_EQ(tr.floor(), 1);
}

TEST(FloorTracker, RampUpFromTheSegmentersZThenItsOffsetIsDropped) {
  FloorTracker tr(two_floors(), 0);
  const double x = drive_ramp(tr, false, true);
  EXPECT_GT(x, 14.5);
  EXPECT_LT(x, 16.5);
  EXPECT_EQ(tr.floor(), 1);
  EXPECT_EQ(tr.z_offset(), 0.0);
  EXPECT_NE(tr.status_text().find("offset +3.30 m dropped"), std::string::npos) << tr.status_text();
}

TEST(FloorTracker, FlatDrivingThroughAConnectionAreaStays) {
  FloorTracker tr(two_floors(), 0);
  ImuGen gen;
  int64_t frame_us = 0;
  for (int64_t us = 0; us < 60'000'000; us += 5000) {
    const double t = us * 1e-6, x = 0.5 * t;
    // Wobble, and a forward acceleration at the start (tilts the specific force).
    tr.add_imu(us, gen(0.01 * std::sin(2 * t), 0.01 * std::sin(1.7 * t) - (t < 1.5 ? 0.035 : 0), 0));
    if (us < frame_us) continue;
    frame_us += 100000;
    FloorObservation o;
    o.utime = us;
    o.pose = {x, 1, 0};
    o.z = 1.2 + 0.04 * std::sin(0.5 * t);
    o.z_known = true;
    EXPECT_FALSE(tr.update(o)) << "x " << x << ": " << tr.status_text();
  }
  EXPECT_EQ(tr.floor(), 0);
}

namespace {

// Frames standing at p every 0.1 s without IMU; the plan's inlier ratio drops to `ratio` from t = 5 s.
std::vector<FloorProbe> stand_until_probe(FloorTracker& tr, const Eigen::Vector2d& p, double ratio, bool lost, int64_t* us) {
  for (; *us < 20'000'000; *us += 100000) {
    FloorObservation o;
    o.utime = *us;
    o.pose = {p.x(), p.y(), 0.3};
    const bool bad = *us >= 5'000'000;
    o.inlier_ratio = bad ? ratio : 0.95;
    o.pose_ok = !(bad && lost);
    o.z = 1.2;
    o.z_known = true;
    EXPECT_FALSE(tr.update(o));
    if (!tr.probe_request().empty()) return tr.probe_request();
  }
  return {};
}

}  // namespace

TEST(FloorTracker, PlanMismatchInALiftAreaProbesTheOtherFloorsAndSwitches) {
  FloorTracker tr(two_floors(), 0);
  int64_t us = 0;
  const auto q = stand_until_probe(tr, {1, 6}, 0.2, true, &us);
  ASSERT_EQ(q.size(), 2u);
  EXPECT_NEAR(us * 1e-6, 5.2, 1e-6);  // the third frame that did not match
  EXPECT_EQ(q[0].floor, 0);           // the current floor first (the same search)
  EXPECT_EQ(q[1].floor, 1);
  EXPECT_EQ(q[1].name, "first");
  EXPECT_NEAR(q[1].search_center.x(), 1, 1e-9);
  EXPECT_NEAR(tr.pose_z(), 1.2, 1e-9);
  const auto s = tr.probe_result({{0, false, 0.2}, {1, true, 0.93}});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->to_name, "first");
  EXPECT_EQ(s->via.name, "lift");
  EXPECT_EQ(tr.floor(), 1);
  EXPECT_NE(s->reason.find("the plan of 'ground' no longer matches in lift 'lift'"), std::string::npos) << s->reason;
  EXPECT_NE(s->reason.find("no IMU"), std::string::npos) << s->reason;
  EXPECT_NE(s->reason.find("'first' matches 93 %"), std::string::npos) << s->reason;
  // No IMU to follow the ride: z jumps to the new floor, and says so.
  EXPECT_NEAR(tr.pose_z(), 3.3 + 1.2, 1e-9);
  EXPECT_NE(tr.status_text().find("z 1.20 m -> 4.50 m"), std::string::npos) << tr.status_text();
}

TEST(FloorTracker, PlanMismatchStaysWhenNoOtherFloorMatchesBetter) {
  FloorTracker tr(two_floors(), 0);
  int64_t us = 0;
  ASSERT_EQ(stand_until_probe(tr, {1, 6}, 0.4, false, &us).size(), 2u);
  EXPECT_FALSE(tr.probe_result({{0, true, 0.45}, {1, true, 0.55}}));  // better, but not by the margin
  EXPECT_EQ(tr.floor(), 0);
  EXPECT_NE(tr.status_text().find("staying on 'ground'"), std::string::npos) << tr.status_text();
  // The next probe comes probe_every_frames later.
  us += 100000;
  const auto q = stand_until_probe(tr, {1, 6}, 0.4, false, &us);
  EXPECT_NEAR(us * 1e-6, 5.7, 1e-6);
  EXPECT_EQ(q.size(), 2u);
}

TEST(FloorTracker, PlanMismatchOutsideALiftAreaProbesNothing) {
  FloorTracker tr(two_floors(), 0);
  int64_t us = 0;
  EXPECT_TRUE(stand_until_probe(tr, {6, 6}, 0.1, true, &us).empty());
  EXPECT_EQ(tr.floor(), 0);
}

TEST(FloorTracker, ASegmenterZOffTheBuildingIsNotUsedAndSaid) {
  FloorTracker tr(two_floors(), 0);
  for (int k = 0; k < 200; ++k) {
    FloorObservation o;
    o.utime = int64_t(k) * 100000;
    o.pose = {3 + 0.01 * k, 10, 0};
    o.z_known = true;
    // 1.2 m, then 8 s of a segmenter 15 cm too high (a ceiling of another height), then right again.
    o.z = 1.2 + 0.003 * std::sin(0.3 * k) + (k >= 100 && k < 180 ? 0.15 : 0.0);
    EXPECT_FALSE(tr.update(o));
    EXPECT_NEAR(tr.pose_z(), 1.2, 0.01) << k << ": " << tr.z_source();
    if (k == 120) {  // gated for 2 s: the last good height above the floor
      EXPECT_NE(tr.z_source().find("building: last good height 1.20 m"), std::string::npos) << tr.z_source();
      EXPECT_NE(tr.status_text().find("+0.15 m off"), std::string::npos) << tr.status_text();
      EXPECT_NEAR(tr.pose_z_sigma(0.005), 0.03, 1e-9);
    }
    if (k == 170)  // gated for 7 s: the nominal height
      EXPECT_NE(tr.z_source().find("building: nominal height 1.20 m"), std::string::npos) << tr.z_source();
  }
  EXPECT_NE(tr.status_text().find("the segmenter's again"), std::string::npos) << tr.status_text();
  EXPECT_NEAR(tr.nominal_z().value_or(0), 1.2, 0.005);  // the wrong z did not teach the nominal height
}

// The segmenter's z steps by 5.4 cm for two frames (it took another surface for the one under the robot):
// not used, the last good height instead. A real step (onto a platform, 4 cm) is taken on its third frame.
// Without the rule (a gate of 1 m) the two frames show through.
TEST(FloorTracker, AStepInTheSegmentersZIsUsedOnlyOnceItRepeats) {
  for (const double gate : {FloorTrackerConfig{}.z_step_gate_m, 1.0}) {
    FloorTrackerConfig cfg;
    cfg.z_step_gate_m = gate;
    FloorTracker tr(two_floors(), 0, cfg);
    double worst_glitch = 0;
    for (int k = 0; k < 200; ++k) {
      FloorObservation o;
      o.utime = int64_t(k) * 100000;
      o.pose = {3 + 0.02 * k, 10, 0};
      o.z_known = true;
      const double truth = 1.2 + 0.002 * std::sin(0.3 * k) + (k >= 150 ? 0.04 : 0.0);
      o.z = truth + (k == 100 || k == 101 ? -0.054 : 0.0);
      tr.update(o);
      if (k == 100 || k == 101) worst_glitch = std::max(worst_glitch, std::abs(tr.pose_z() - truth));
      if (gate < 1 && (k == 150 || k == 151)) {
        EXPECT_NEAR(tr.pose_z(), 1.2, 0.005) << k;  // not yet: held at the last good height
        EXPECT_NE(tr.z_source().find("jumped +0.04"), std::string::npos) << tr.z_source();
      }
      if (k >= 152) EXPECT_NEAR(tr.pose_z(), truth, 1e-9) << k << ": " << tr.z_source();
    }
    if (gate < 1) EXPECT_LT(worst_glitch, 0.005);
    else EXPECT_GT(worst_glitch, 0.05);
  }
}

// On the ramp the segmenter measures its z above the ground floor's level, then sees no plane for 10 frames
// (0.5 m of travel, 16 cm of climb) and sends its last z as a prediction with a growing sigma (unknown from
// the 6th frame on): the pose's z follows the ramp's surface (the last good height above it), where holding
// the segmenter's z would lag by up to 16 cm.
TEST(FloorTracker, APredictedZOnARampFollowsTheSurface) {
  FloorTracker tr(two_floors(), 0);
  const double slope = 3.3 / 10;
  double last = 1.2, sigma = 0;
  for (int64_t us = 0; us < 30'000'000; us += 100000) {
    const double x = 0.5 * us * 1e-6;
    FloorObservation o;
    o.utime = us;
    o.pose = {x, 1, 0};
    o.z_known = true;
    const double climb = std::clamp((x - 10) * slope, 0.0, 3.3);
    if (x > 13 && x <= 13.5) {
      sigma = sigma == 0 ? 0.05 : 2 * sigma;  // the segmenter's hold: 0.05 m, doubling per scan
      o.z = last;
      o.z_sigma = sigma;
      o.z_known = sigma < 1.0;
    } else {
      sigma = 0;
      o.z = last = 1.2 + climb;  // above the ground floor's level (its plane seen behind the ramp's foot)
      o.z_sigma = 0.003;
    }
    tr.update(o);
    if (x > 13 && x <= 13.5) EXPECT_NEAR(tr.pose_z(), 1.2 + climb, 0.01) << "x " << x << ": " << tr.z_source();
  }
}
