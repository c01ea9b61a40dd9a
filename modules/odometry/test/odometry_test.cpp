#include <gtest/gtest.h>

#include <cmath>

#include "fploc/odometry/odometry.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::odometry;
using fploc::testing::synth_frame;
using fploc::testing::SynthOptions;

namespace {
Pose2 truth_at(double t) { return {3.0 + 0.6 * t, 3.0 + 1.5 * std::sin(0.25 * t), 0.2 * std::sin(0.3 * t) + 0.1 * t}; }
}  // namespace

TEST(Odometry2D, FollowsANoiseFreeSequence) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  Odometry2D odo;
  odo.set_pose(truth_at(0));
  double max_err = 0;
  int keys = 0;
  for (int k = 0; k < 100; ++k) {
    const double t = 0.1 * k;
    const Pose2 truth = truth_at(t);
    const OdometryResult r = odo.process(synth_frame(plan, truth, SynthOptions{}, int64_t(std::llround(t * 1e6))));
    ASSERT_TRUE(r.ok) << k;
    keys += r.keyframe;
    max_err = std::max(max_err, std::hypot(r.pose.x - truth.x, r.pose.y - truth.y));
  }
  EXPECT_LT(max_err, 0.02);
  EXPECT_GT(keys, 10);
  EXPECT_GT(odo.map_points(), 1000u);
}

TEST(Odometry2D, DriftsWithNoiseButStaysOnTrack) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  Odometry2D odo;
  odo.set_pose(truth_at(0));
  double err = 0;
  for (int k = 0; k < 100; ++k) {
    const double t = 0.1 * k;
    SynthOptions so;
    so.noise_sigma = 0.03;
    so.clutter_fraction = 0.1;
    so.seed = uint32_t(k + 3);
    const Pose2 truth = truth_at(t);
    const OdometryResult r = odo.process(synth_frame(plan, truth, so, int64_t(std::llround(t * 1e6))));
    err = std::hypot(r.pose.x - truth.x, r.pose.y - truth.y);
    if (getenv("ODO_DEBUG")) std::printf("%d ok %d inl %d/%d it %d err %.3f\n", k, r.ok, r.num_inliers, r.num_points, r.iterations, err);
  }
  EXPECT_LT(err, 0.5);
}

TEST(Odometry2D, RefusesGarbage) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  Odometry2D odo;
  odo.set_pose({5, 5, 0});
  EXPECT_TRUE(odo.process(synth_frame(plan, {5, 5, 0}, SynthOptions{}, 0)).ok);
  auto bad = fploc::testing::random_frame(300, 8, 5);
  bad.utime = 100000;
  const OdometryResult r = odo.process(bad);
  EXPECT_FALSE(r.ok);
  EXPECT_NEAR(r.pose.x, 5, 1e-9);
}

// A 4 m wide corridor whose only features along it are cabinets against the walls (1.2 x 0.8 m, every 4 m on
// alternate walls), walked at 0.8 m/s along its middle while four people (0.22 m radius) overtake at 1.5-1.7 m/s, 0.8 m
// to either side. Registered against every point, the people's trail in the local map drags the pose along with them;
// with only static points (a map point another keyframe saw on the same line) and the constant-velocity prediction as a
// prior the pose keeps to the cabinets and the velocity (the prior alone: 0.18 m).
TEST(Odometry2D, StaticPointsAndThePredictionKeepACorridorFromFollowingACrowd) {
  const double v = 0.8;
  auto truth = [&](double t) { return Pose2{1.0 + v * t, 2.0, 0.0}; };
  auto world_at = [&](double t) {
    FloorPlan w;
    w.elements.push_back(Element::segment({-100, 0}, {100, 0}));
    w.elements.push_back(Element::segment({-100, 4}, {100, 4}));
    for (int k = -4; k < 20; ++k) {
      const double x = 4.0 * k + (k % 2 ? 2.0 : 0.0);
      const double y0 = k % 2 ? 4.0 : 0.0, y1 = k % 2 ? 3.2 : 0.8;
      w.elements.push_back(Element::segment({x, y0}, {x, y1}));
      w.elements.push_back(Element::segment({x, y1}, {x + 1.2, y1}));
      w.elements.push_back(Element::segment({x + 1.2, y1}, {x + 1.2, y0}));
    }
    const double people[][3] = {{-8.0, 1.2, 1.5}, {-9.0, 2.8, 1.7}, {-10.5, 1.2, 1.6}, {-12.0, 2.8, 1.5}};
    for (const auto& p : people) w.elements.push_back(Element::circle({p[0] + p[2] * t, p[1]}, 0.22));
    return w;
  };
  auto run = [&](const OdometryConfig& c) {
    Odometry2D odo(c);
    odo.set_pose(truth(0), Eigen::Vector3d(v, 0, 0));
    double err = 0;
    for (int k = 0; k < 120; ++k) {
      const double t = 0.1 * k;
      SynthOptions so;
      so.max_range = 8;
      so.noise_sigma = 0.01;
      so.seed = uint32_t(k + 7);
      const OdometryResult r = odo.process(synth_frame(world_at(t), truth(t), so, int64_t(std::llround(t * 1e6))));
      err = std::hypot(r.pose.x - truth(t).x, r.pose.y - truth(t).y);
      if (getenv("ODO_DEBUG")) std::printf("%d ok %d inl %d/%d err %.3f\n", k, r.ok, r.num_inliers, r.num_points, err);
    }
    return err;
  };
  OdometryConfig every_point;
  every_point.max_points = 250;
  OdometryConfig held = every_point;
  held.static_support_m = 0.05;
  held.prediction_sigma_m = 0.01;
  held.prediction_sigma_rad = 0.005;
  OdometryConfig static_only = every_point, prior_only = every_point;
  static_only.static_support_m = 0.05;
  prior_only.prediction_sigma_m = 0.01;
  prior_only.prediction_sigma_rad = 0.005;
  const double e_every = run(every_point), e_held = run(held), e_static = run(static_only), e_prior = run(prior_only);
  std::printf("after 4.7 m: every point %.3f m, static points %.3f, prior %.3f, both %.3f\n", e_every, e_static, e_prior, e_held);
  EXPECT_GT(e_every, 0.3);
  EXPECT_LT(e_held, 0.1);
}

// In a round room seen from its centre every frame's points are the same whatever the heading: the registration
// cannot see the robot turn (as it cannot tell people turning with it from the robot turning). A measured yaw
// change (a gyro's integral, set_yaw_change) carries the heading; without it the odometry keeps its (unknown) yaw.
TEST(Odometry2D, AMeasuredYawChangeTurnsWhatThePointsCannot) {
  FloorPlan room;
  room.elements.push_back(Element::circle({5, 5}, 4.0));
  const double w = 0.2;  // rad/s
  auto truth = [&](double t) { return Pose2{5, 5, w * t}; };
  auto run = [&](bool gyro) {
    Odometry2D odo;
    odo.set_pose(truth(0));
    double err = 0;
    for (int k = 0; k < 50; ++k) {
      const double t = 0.1 * k;
      SynthOptions so;
      so.noise_sigma = 0.005;
      so.seed = uint32_t(k + 11);
      if (gyro && k > 0) odo.set_yaw_change(w * 0.1, 0.002);
      const OdometryResult r = odo.process(synth_frame(room, truth(t), so, int64_t(std::llround(t * 1e6))));
      EXPECT_TRUE(r.ok) << k;
      err = std::max(err, std::abs(wrap_angle(r.pose.yaw - truth(t).yaw)));
      EXPECT_LT(std::hypot(r.pose.x - 5, r.pose.y - 5), 0.02) << k;
    }
    return err;
  };
  const double without = run(false), with = run(true);
  std::printf("heading error after 4.9 s: points alone %.3f rad, with the gyro %.4f rad\n", without, with);
  EXPECT_GT(without, 0.5);
  EXPECT_LT(with, 0.01);
}
