#include "fploc/adapters/features_t.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace fploc;

TEST(FeaturesAdapter, FromMsgDropsNonFiniteAndNamesBadArrays) {
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
  m.status = 1;
  int dropped = 0;
  const FeatureFrame f = adapters::from_msg(m, &dropped);
  EXPECT_EQ(dropped, 1);
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_EQ(f.points[0].kind, FeatureKind::kCorner);
  EXPECT_EQ(f.points[1].group, 2);
  EXPECT_FLOAT_EQ(f.points[1].t, 0.09f);
  EXPECT_EQ(f.scan_seq, 7);
  EXPECT_EQ(f.status, FeatureStatus::kFewFeatures);
  EXPECT_DOUBLE_EQ(f.z, 1.5);
  m.num_points = 4;
  try {
    adapters::from_msg(m);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("num_points 4"), std::string::npos) << e.what();
  }
}

TEST(FeaturesAdapter, RoundTrip) {
  FeatureFrame f;
  f.utime = 42;
  f.scan_seq = 9;
  f.status = FeatureStatus::kOk;
  f.roll = 0.01;
  f.pitch = -0.02;
  f.z = 1.2;
  f.z_sigma = kUnknownZSigmaM;
  f.roll_pitch_sigma = 0.001;
  f.attitude_t = 0.05;
  f.num_groups = 1;
  f.points = {{{1.25, -2.5}, FeatureKind::kSurface, 0, 0.01f}, {{3.0, 0.5}, FeatureKind::kCorner, -1, 0.02f}};
  features_t m;
  adapters::to_msg(f, 17, m);
  EXPECT_EQ(m.seq, 17);
  EXPECT_EQ(m.scan_seq, 9);
  EXPECT_EQ(m.num_points, 2);
  const FeatureFrame g = adapters::from_msg(m);
  ASSERT_EQ(g.points.size(), 2u);
  EXPECT_EQ(g.points[0].p, f.points[0].p);
  EXPECT_EQ(g.points[1].kind, FeatureKind::kCorner);
  EXPECT_EQ(g.points[1].t, 0.02f);
  EXPECT_EQ(g.num_groups, 1);
  EXPECT_EQ(g.z_sigma, kUnknownZSigmaM);
  EXPECT_FALSE(z_known(g));
  EXPECT_TRUE(roll_pitch_known(g));
  EXPECT_EQ(g.attitude_t, 0.05);
}
