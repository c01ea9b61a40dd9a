#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fploc/nodes/localization_convert.h"

using namespace fploc;

TEST(LocalizationConvert, FeaturesRoundTripAndBadArrays) {
  features_t m{};
  m.utime = 123;
  m.scan_seq = 7;
  m.num_points = 3;
  m.x = {1.f, std::numeric_limits<float>::quiet_NaN(), 3.f};
  m.y = {4.f, 5.f, 6.f};
  m.kind = {0, 1, 1};
  m.group = {-1, 2, 2};
  m.t_offset_s = {0.f, 0.05f, 0.09f};
  m.z = 1.5;
  int dropped = 0;
  const FeatureFrame f = from_msg(m, &dropped);
  EXPECT_EQ(dropped, 1);
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_EQ(f.points[0].kind, FeatureKind::kCorner);
  EXPECT_EQ(f.points[1].group, 2);
  EXPECT_FLOAT_EQ(f.points[1].t, 0.09f);
  EXPECT_EQ(f.scan_seq, 7);
  EXPECT_DOUBLE_EQ(f.z, 1.5);
  m.num_points = 4;
  EXPECT_THROW(from_msg(m), std::runtime_error);
}

TEST(LocalizationConvert, PoseMessageCarriesYawAndCovariance) {
  Eigen::Matrix3d c;
  c << 1, 0.1, 0.2, 0.1, 2, 0.3, 0.2, 0.3, 3;
  const pose_t m = make_pose_msg(5, 1, Pose2{1, 2, 2.5}, 0.01, -0.02, 1.4, c, 0.05, 0.002, 0, true, false);
  const Pose2 p = pose2_of(m);
  EXPECT_NEAR(p.x, 1, 1e-12);
  EXPECT_NEAR(p.yaw, 2.5, 1e-9);
  EXPECT_DOUBLE_EQ(m.position[2], 1.4);
  EXPECT_DOUBLE_EQ(m.covariance[0 * 6 + 5], 0.2);   // x-yaw
  EXPECT_DOUBLE_EQ(m.covariance[5 * 6 + 5], 3.0);   // yaw-yaw
  EXPECT_DOUBLE_EQ(m.covariance[2 * 6 + 2], 0.05 * 0.05);
  EXPECT_TRUE(m.keyframe);
  EXPECT_FALSE(m.final_estimate);
}
