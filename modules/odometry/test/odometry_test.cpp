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
