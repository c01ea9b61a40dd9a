#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "fploc/eval/uncertainty.h"

using namespace fploc;
using namespace fploc::eval;

namespace {
Trajectory line_traj(int n) {
  Trajectory t;
  for (int i = 0; i < n; ++i) t.push_back(StampedPose::from_rpy(0.1 * i, Eigen::Vector3d(0.1 * i, 0.5, 1.0), 0, 0, 0.01 * i));
  return t;
}
}  // namespace

// Errors drawn from the covariance itself give a NEES near the degrees of freedom; a covariance 100x too
// small gives ~100x that.
TEST(Uncertainty, NeesOfAConsistentEstimatorIsTheDegreesOfFreedom) {
  const Trajectory gt = line_traj(4000);
  Eigen::Matrix3d P;
  P << 0.04 * 0.04, 0.0005, 0, 0.0005, 0.03 * 0.03, 0, 0, 0, 0.01 * 0.01;
  const Eigen::Matrix3d L = P.llt().matrixL();
  std::mt19937 rng(5);
  std::normal_distribution<double> nd;
  Trajectory est;
  std::vector<PoseUncertainty> u, u_small;
  for (const auto& g : gt) {
    const Eigen::Vector3d e = L * Eigen::Vector3d(nd(rng), nd(rng), nd(rng));
    const double yaw = std::atan2(g.iso().linear()(1, 0), g.iso().linear()(0, 0));
    est.push_back(StampedPose::from_rpy(g.t, g.p - Eigen::Vector3d(e.x(), e.y(), 0), 0, 0, yaw - e.z()));
    u.push_back({g.t, 0, P});
    u_small.push_back({g.t, 0, P / 100});
  }
  const auto pairs = associate(gt, est);
  const Consistency c = consistency(gt, est, pairs, u);
  EXPECT_EQ(c.poses, gt.size());
  EXPECT_EQ(c.nees_poses, gt.size());
  EXPECT_NEAR(c.nees.mean, 3.0, 0.15);
  EXPECT_NEAR(c.nees_x.mean, 1.0, 0.08);
  EXPECT_NEAR(c.nees_y.mean, 1.0, 0.08);
  EXPECT_NEAR(c.nees_yaw.mean, 1.0, 0.08);
  EXPECT_EQ(c.ok, gt.size());
  EXPECT_EQ(c.false_ok, 0u);
  const Consistency s = consistency(gt, est, pairs, u_small);
  EXPECT_NEAR(s.nees.mean / c.nees.mean, 100.0, 1.0);
}

// The false-OK counter: only poses with status OK and a horizontal error above the threshold count.
TEST(Uncertainty, FalseOkCountsOkPosesWithLargeHorizontalError) {
  const Trajectory gt = line_traj(10);
  Trajectory est = gt;
  std::vector<PoseUncertainty> u;
  for (const auto& g : gt) u.push_back({g.t, 0, Eigen::Matrix3d::Identity() * 0.01});
  est[2].p.x() += 0.5;   // OK and 0.5 m off: false OK
  est[3].p.z() += 0.5;   // vertical error only: not horizontal
  est[4].p.y() += 0.31;  // OK and 0.31 m off: false OK
  est[5].p.y() += 0.29;  // within 0.3 m
  est[6].p.x() += 2.0;
  u[6].status = 1;       // POOR: honest
  est[7].p.x() += 2.0;
  u[7].status = 2;       // LOST: honest
  const Consistency c = consistency(gt, est, associate(gt, est), u);
  EXPECT_EQ(c.poses, 10u);
  EXPECT_EQ(c.ok, 8u);
  EXPECT_EQ(c.false_ok, 2u);
  EXPECT_DOUBLE_EQ(c.false_ok_share, 0.2);
  // A pose without an uncertainty record is not counted; a singular covariance is left out of the NEES.
  u.erase(u.begin() + 9);
  u[0].cov.setZero();
  const Consistency d = consistency(gt, est, associate(gt, est), u);
  EXPECT_EQ(d.poses, 9u);
  EXPECT_EQ(d.nees_poses, 8u);
}

TEST(Uncertainty, FileRoundTripAndBadLines) {
  const auto p = std::filesystem::temp_directory_path() / "fploc-uncertainty-test.txt";
  PoseUncertainty a{1700000000.123456, 1, Eigen::Matrix3d::Identity()};
  a.cov(0, 1) = a.cov(1, 0) = 0.25;
  a.cov(1, 2) = a.cov(2, 1) = -0.125;
  std::ofstream(p) << "# t status xx xy xyaw yy yyaw yawyaw\n" << uncertainty_line(a) << "\n";
  auto r = read_uncertainty(p.string());
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].t, a.t, 1e-6);
  EXPECT_EQ(r[0].status, 1);
  EXPECT_TRUE(r[0].cov.isApprox(a.cov));
  std::ofstream(p) << uncertainty_line(a) << "\n1700000001 0 1 2 3\n";
  try {
    read_uncertainty(p.string());
    ADD_FAILURE() << "a short line was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p.string() + ":2:"), std::string::npos) << e.what();
  }
  std::ofstream(p) << "1700000001 7 1 0 0 1 0 1\n";
  EXPECT_THROW(read_uncertainty(p.string()), std::runtime_error);
  std::filesystem::remove(p);
  EXPECT_THROW(read_uncertainty(p.string()), std::runtime_error);
}
