// A laser's mount from tf (laser_mounts.h): composed through the tree, level or tilting, upside down.
#include "laser_mounts.h"

#include <gtest/gtest.h>

#include <cmath>

using fploc::import::laser_mount;
using fploc::import::TfTree;

namespace {
fploc::rec::Transform tf(const std::string& parent, const std::string& child, int64_t t_ns, Eigen::Vector3d p,
                         const Eigen::Quaterniond& q) {
  fploc::rec::Transform t;
  t.header.frame_id = parent;
  t.header.stamp_ns = t_ns;
  t.child_frame_id = child;
  t.t = {p.x(), p.y(), p.z()};
  t.q = {q.x(), q.y(), q.z(), q.w()};
  return t;
}
Eigen::Quaterniond about(const Eigen::Vector3d& axis, double deg) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(deg * M_PI / 180, axis));
}
}  // namespace

TEST(LaserMount, ComposedThroughTheTreeLevelTiltingAndUpsideDown) {
  TfTree tree;
  // base_link -> mount (static, 0.5 m ahead) -> tilt laser nodding 0..40 deg in pitch over 4 s.
  tree.add(tf("/base_link", "mount", 0, {0.5, 0, 0.3}, Eigen::Quaterniond::Identity()));
  for (int k = 0; k <= 40; ++k)
    tree.add(tf("mount", "tilt_laser", k * 100'000'000LL, {0, 0, 0.1}, about(Eigen::Vector3d::UnitY(), k)));
  // base_link -> back laser: 0.4 m behind, facing back, upside down (rolled 180 deg).
  tree.add(tf("base_link", "back_laser", 0, {-0.4, 0.05, 0.2},
              about(Eigen::Vector3d::UnitZ(), 180) * about(Eigen::Vector3d::UnitX(), 180)));
  tree.sort();
  EXPECT_EQ(fploc::import::robot_frame(tree, ""), "base_link");
  EXPECT_EQ(fploc::import::robot_frame(tree, "/mount"), "mount");

  const auto tilt = laser_mount(tree, "base_link", "/front", "/tilt_laser");
  ASSERT_TRUE(tilt.found) << tilt.why;
  EXPECT_NEAR(tilt.tilt_min_deg, 0, 1e-6);
  EXPECT_NEAR(tilt.tilt_max_deg, 40, 1e-6);
  EXPECT_FALSE(tilt.level());
  EXPECT_NE(tilt.describe().find("tilting"), std::string::npos) << tilt.describe();

  const auto back = laser_mount(tree, "base_link", "/back", "back_laser");
  ASSERT_TRUE(back.found) << back.why;
  EXPECT_TRUE(back.level());
  EXPECT_TRUE(back.upside_down);
  EXPECT_NEAR(std::abs(back.yaw_deg), 180, 1e-6);
  EXPECT_NEAR(back.x_m, -0.4, 1e-12);
  EXPECT_NEAR(back.y_m, 0.05, 1e-12);

  const auto lost = laser_mount(tree, "base_link", "/x", "no_such_frame");
  EXPECT_FALSE(lost.found);
  EXPECT_NE(lost.why.find("no tf frame 'no_such_frame'"), std::string::npos) << lost.why;
  EXPECT_FALSE(laser_mount(tree, "base_link", "/y", "").found);
}

// The mean mount is a mean over time, not over tf samples: a stretch where tf was published densely must not
// outweigh a longer one sampled rarely (it was weighted per sample: 0.216 m here instead of 0.37 m).
TEST(LaserMount, MeanWeighsTimeNotSamplesUnevenSpacing) {
  TfTree tree;
  const auto id = Eigen::Quaterniond::Identity();
  for (int k = 0; k <= 100; ++k) tree.add(tf("base_link", "laser", k * 10'000'000LL, {0.2, 0, 0.3}, id));  // 0..1 s, 100 Hz
  for (int k = 2; k <= 10; ++k) tree.add(tf("base_link", "laser", k * 1'000'000'000LL, {0.4, 0, 0.3}, id));  // 2..10 s, 1 Hz
  tree.sort();
  const auto m = laser_mount(tree, "base_link", "/scan", "laser");
  ASSERT_TRUE(m.found) << m.why;
  // 0.2 m for 1 s, 0.2 -> 0.4 m interpolated over 1 s, 0.4 m for 8 s.
  EXPECT_NEAR(m.x_m, (0.2 * 1 + 0.3 * 1 + 0.4 * 8) / 10, 1e-9);
  EXPECT_NEAR(m.z_m, 0.3, 1e-12);
}

// fploc import keeps tf every 100 ms at most and not a value published again unchanged: a mount that held one value
// for 9 s (re-published at 50 Hz, as a static transform sent on /tf is) and then jittered for 1 s is still 9 s of the
// first value, through a static edge also re-published at 50 Hz. Before, the held value was one sample against the
// jitter's ten (0.475 m), and with the repeats dropped it blended into the next value over the whole 9 s.
TEST(LaserMount, AValuePublishedAgainAndAgainKeepsItsTime) {
  TfTree tree(100'000'000);
  const auto id = Eigen::Quaterniond::Identity();
  for (int k = 0; k < 500; ++k) {  // 0 .. 9.98 s at 50 Hz
    const int64_t t = k * 20'000'000LL;
    tree.add(tf("base_link", "mount", t, {0.1, 0, 0.2}, id));
    const double x = k < 450 ? 0.1 : 0.4 + (k % 2 ? 0.001 : -0.001);  // from 9 s: 0.4 m, jittering
    tree.add(tf("mount", "laser", t, {x, 0, 0.1}, id));
  }
  tree.sort();
  const auto m = laser_mount(tree, "base_link", "/scan", "laser");
  ASSERT_TRUE(m.found) << m.why;
  // 0.2 m in base_link for 8.98 s, then 0.5 m (+- 1 mm) for 1 s: about 0.23 m.
  EXPECT_NEAR(m.x_m, (0.2 * 8.98 + 0.35 * 0.02 + 0.5 * 0.98) / 9.98, 0.002);
  EXPECT_NEAR(m.z_m, 0.3, 1e-12);
  EXPECT_TRUE(m.level());
}
