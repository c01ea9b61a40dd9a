#include "fploc/adapters/pose_t.h"

#include <gtest/gtest.h>

using namespace fploc;

TEST(PoseAdapter, CarriesYawCovarianceAndSigmas) {
  Eigen::Matrix3d c;
  c << 1, 0.1, 0.2, 0.1, 2, 0.3, 0.2, 0.3, 3;
  const pose_t m = adapters::make_pose_msg(5, 1, Pose2{1, 2, 2.5}, 0.01, -0.02, 1.4, c, 0.05, 0.002, 0, true, false);
  const Pose2 p = adapters::pose2_of(m);
  EXPECT_NEAR(p.x, 1, 1e-12);
  EXPECT_NEAR(p.yaw, 2.5, 1e-9);
  EXPECT_DOUBLE_EQ(m.position[2], 1.4);
  EXPECT_DOUBLE_EQ(m.covariance[0 * 6 + 5], 0.2);   // x-yaw
  EXPECT_DOUBLE_EQ(m.covariance[5 * 6 + 5], 3.0);   // yaw-yaw
  EXPECT_DOUBLE_EQ(m.covariance[2 * 6 + 2], 0.05 * 0.05);
  EXPECT_TRUE(m.keyframe);
  EXPECT_FALSE(m.final_estimate);
}

TEST(PoseAdapter, LocalizedPoseCarriesItsOwnSigmas) {
  optimizer::PoseOut p;
  p.utime = 7;
  p.pose = {3, 4, -1};
  p.z = 1.1;
  p.z_sigma = 0.02;
  p.roll_pitch_sigma = 0.004;
  p.final_estimate = true;
  const pose_t m = adapters::to_msg(p, 3);
  EXPECT_EQ(m.seq, 3);
  EXPECT_EQ(m.utime, 7);
  EXPECT_DOUBLE_EQ(m.covariance[2 * 6 + 2], 0.02 * 0.02);
  EXPECT_DOUBLE_EQ(m.covariance[3 * 6 + 3], 0.004 * 0.004);
  EXPECT_TRUE(m.final_estimate);
}
