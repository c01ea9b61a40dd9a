#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "fploc/core/pose.h"

using namespace fploc;

TEST(Pose, WrapAngle) {
  EXPECT_NEAR(wrap_angle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrap_angle(-3 * M_PI / 2), M_PI / 2, 1e-12);
  EXPECT_NEAR(wrap_angle(0.3), 0.3, 1e-15);
}

TEST(Pose, RpyRoundTrip) {
  auto s = StampedPose::from_rpy(1.0, {1, 2, 3}, 0.05, -0.03, 2.5);
  auto rpy = s.rpy();
  EXPECT_NEAR(rpy.x(), 0.05, 1e-12);
  EXPECT_NEAR(rpy.y(), -0.03, 1e-12);
  EXPECT_NEAR(rpy.z(), 2.5, 1e-12);
}

TEST(Tum, WriteReadRoundTrip) {
  Trajectory t;
  for (int i = 0; i < 5; ++i) t.push_back(StampedPose::from_rpy(100.0 + i * 0.1, {i * 0.5, -i * 0.25, 1.2}, 0.01, 0.02, i * 0.3));
  const std::string path = testing::TempDir() + "/rt.tum";
  write_tum(path, t);
  auto r = read_tum(path);
  ASSERT_EQ(r.size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(r[i].t, t[i].t, 1e-6);
    EXPECT_NEAR((r[i].p - t[i].p).norm(), 0, 1e-6);
    EXPECT_NEAR(r[i].q.angularDistance(t[i].q), 0, 1e-7);
  }
}

TEST(Tum, BadRowNamesLine) {
  const std::string path = testing::TempDir() + "/bad.tum";
  std::ofstream(path) << "# comment\n1 0 0 0 0 0 0 1\n2 0 0 zero 0 0 0 1\n";
  try {
    read_tum(path);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.tum:3:"), std::string::npos) << e.what();
  }
}

TEST(Pose, InterpolateScalesTheIncrement) {
  const Pose2 a{1, 2, 3.0}, b = compose(a, Pose2{0.4, -0.2, 0.5});
  for (double f : {0.0, 0.25, 1.0}) {
    const Pose2 p = interpolate(a, b, f);
    const Pose2 d = between(a, p);
    EXPECT_NEAR(d.x, 0.4 * f, 1e-12);
    EXPECT_NEAR(d.y, -0.2 * f, 1e-12);
    EXPECT_NEAR(d.yaw, 0.5 * f, 1e-12);
  }
  // Across +-pi the short way round.
  const Pose2 c{0, 0, 3.1}, e{0, 0, -3.1};
  EXPECT_NEAR(std::abs(interpolate(c, e, 0.5).yaw), M_PI, 1e-9);
}
