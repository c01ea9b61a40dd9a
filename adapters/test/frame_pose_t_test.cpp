#include "fploc/adapters/frame_pose_t.h"

#include <gtest/gtest.h>

#include <limits>

using namespace fploc;

TEST(FramePoseAdapter, RoundTripAndSanitising) {
  localizer::FramePose f;
  f.utime = 100;
  f.scan_seq = 4;
  f.match.status = matcher::FitStatus::kPoor;
  f.match.text = "few inliers";
  f.match.pose = {1, 2, 0.3};
  f.match.twist = {0.5, 0, 0.1};
  f.match.covariance = Eigen::Matrix3d::Identity() * 0.01;
  f.roll = 0.01;
  f.z = 1.3;
  f.floor_index = 1;
  f.floor = "first";
  const frame_pose_t m = adapters::to_msg(f, 11, 0.0);
  EXPECT_EQ(m.seq, 11);
  EXPECT_EQ(m.status, 1);
  EXPECT_EQ(m.status_text, "POOR: few inliers");
  localizer::FramePose g = adapters::from_msg(m);
  EXPECT_EQ(g.match.status, matcher::FitStatus::kPoor);
  EXPECT_EQ(g.match.text, "few inliers");  // the status prefix the wire text carries is not kept twice
  EXPECT_EQ(g.match.pose.yaw, 0.3);
  EXPECT_EQ(g.match.twist.vx, 0.5);
  EXPECT_EQ(g.z, 1.3);
  EXPECT_EQ(m.floor_index, 1);
  EXPECT_EQ(g.floor_index, 1);
  EXPECT_EQ(g.floor, "first");
  frame_pose_t bad = m;
  bad.twist[1] = std::numeric_limits<double>::quiet_NaN();
  bad.status = 9;
  g = adapters::from_msg(bad);
  EXPECT_EQ(g.match.twist.vx, 0.0);
  EXPECT_EQ(g.match.status, matcher::FitStatus::kLost);
}
