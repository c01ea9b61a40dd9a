// tf -> TUM with a sparse edge: map -> odom at 1 Hz (moving 1 m/s in x, turning 0.1 rad/s), odom ->
// base_link at 10 Hz (moving 0.5 m/s in y). The pose at every 10 Hz stamp must use map -> odom
// interpolated at that stamp, not its last sample.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "tum_track.h"

using fploc::import::TumTrack;

namespace {
fploc::rec::Transform tf(const char* parent, const char* child, double t, double x, double y, double yaw) {
  fploc::rec::Transform T;
  T.header.frame_id = parent;
  T.header.stamp_ns = int64_t(std::llround(t * 1e9));
  T.child_frame_id = child;
  T.t[0] = x;
  T.t[1] = y;
  T.t[2] = 0;
  T.q[0] = 0;
  T.q[1] = 0;
  T.q[2] = std::sin(yaw / 2);
  T.q[3] = std::cos(yaw / 2);
  return T;
}
}  // namespace

TEST(TumTrack, InterpolatesASparseEdge) {
  const std::string path = ::testing::TempDir() + "/tum_track_test.tum";
  TumTrack track;
  ASSERT_TRUE(track.open(path, "/map", "base_link"));
  // Record order as a bag has it: each map -> odom sample arrives at its own time.
  for (int k = 0; k <= 30; ++k) {
    const double t = 0.1 * k;
    if (k % 10 == 0) track.tf(tf("map", "odom", t, 1.0 * t, 0, 0.1 * t));
    track.tf(tf("odom", "/base_link", t, 0, 0.5 * t, 0));
  }
  track.close();
  EXPECT_EQ(track.poses(), 31u);
  std::ifstream in(path);
  std::string line;
  int n = 0;
  double worst = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    double t, x, y, z, qx, qy, qz, qw;
    s >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    // map -> odom at t: (t, 0) rotated by 0.1 t; base in odom: (0, 0.5 t).
    const double yaw = 0.1 * t, by = 0.5 * t;
    const double ex = t - std::sin(yaw) * by, ey = std::cos(yaw) * by;
    worst = std::max({worst, std::abs(x - ex), std::abs(y - ey), std::abs(2 * std::atan2(qz, qw) - yaw)});
    ++n;
  }
  EXPECT_EQ(n, 31);
  // Linear interpolation of a uniformly moving edge is exact in translation; the rotation slerps.
  EXPECT_LT(worst, 2e-3) << "the sparse edge was not interpolated";
}

TEST(TumTrack, EdgeAtHoldsOutsideItsSpan) {
  fploc::import::TfTree::Edge e;
  e.parent = "a";
  e.samples.push_back({1000, Eigen::Vector3d(1, 0, 0), Eigen::Quaterniond::Identity()});
  e.samples.push_back({3000, Eigen::Vector3d(3, 0, 0), Eigen::Quaterniond::Identity()});
  EXPECT_NEAR(fploc::import::TfTree::at(e, 0).translation().x(), 1, 1e-12);
  EXPECT_NEAR(fploc::import::TfTree::at(e, 2000).translation().x(), 2, 1e-12);
  EXPECT_NEAR(fploc::import::TfTree::at(e, 2500).translation().x(), 2.5, 1e-12);
  EXPECT_NEAR(fploc::import::TfTree::at(e, 9000).translation().x(), 3, 1e-12);
}
