#include "fploc/eval/online_ate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fploc/eval/eval.h"

using fploc::eval::OnlineAte;

TEST(OnlineAte, MatchesInAnyOrderAndReplacesRepublished) {
  OnlineAte a(0.002);
  EXPECT_TRUE(std::isnan(a.rmse()));
  a.add_truth(1000000, 0, 0, 0);
  a.add_estimate(1000000, 3, 0, 0);
  EXPECT_EQ(a.count(), 1u);
  a.add_estimate(2000500, 0, 2, 0);  // before its truth, 0.5 ms off
  EXPECT_EQ(a.count(), 1u);
  a.add_truth(2000000, 0, 0, 0);
  EXPECT_EQ(a.count(), 2u);
  EXPECT_NEAR(a.rmse(), std::sqrt((9.0 + 4.0) / 2), 1e-12);
  a.add_estimate(1000000, 1, 0, 0);  // the optimizer re-publishes the first pose
  EXPECT_EQ(a.count(), 2u);
  EXPECT_NEAR(a.rmse(), std::sqrt((1.0 + 4.0) / 2), 1e-12);
  EXPECT_NEAR(*a.error(2000500), 2.0, 1e-12);
  a.add_estimate(5000000, 1, 1, 1);  // no truth within 2 ms
  EXPECT_FALSE(a.error(5000000));
}

TEST(OnlineAte, AgreesWithBatchAte) {
  fploc::Trajectory gt, est;
  OnlineAte a(0.002);
  for (int i = 0; i < 200; ++i) {
    const double t = 0.1 * i;
    fploc::StampedPose g, e;
    g.t = t;
    g.p = {std::cos(t), std::sin(t), 0.01 * i};
    e.t = t + 0.0005;
    e.p = g.p + Eigen::Vector3d(0.01 * std::sin(3 * t), -0.02, 0.005);
    gt.push_back(g);
    est.push_back(e);
    a.add_estimate(int64_t(std::llround(e.t * 1e6)), e.p.x(), e.p.y(), e.p.z());
    a.add_truth(int64_t(std::llround(g.t * 1e6)), g.p.x(), g.p.y(), g.p.z());
  }
  const auto pairs = fploc::eval::associate(gt, est, 0.002);
  const auto batch = fploc::eval::ate(gt, est, pairs, fploc::eval::Align::None);
  EXPECT_EQ(a.count(), pairs.size());
  EXPECT_NEAR(a.rmse(), batch.trans.rmse, 1e-9);
}
