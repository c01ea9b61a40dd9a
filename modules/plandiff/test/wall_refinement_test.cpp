// WallRefinement on its own model (plan_diff_test runs it inside PlanDiff on simulated scans).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "fploc/plandiff/wall_refinement.h"

namespace fploc::plandiff {
namespace {

// Walls offset (o_a, o_b) at their ends, seen at random places along them by scans with a registration error
// each: the offsets come back (the prior toward 0 shrinks them by a little).
TEST(WallRefinement, TheWallsEndOffsetsComeBackWithEachScansErrorEliminated) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ut(0.0, 1.0), ub(-0.05, 0.05);
  const double oa[6] = {0.04, -0.03, 0.0, 0.02, 0.05, -0.01}, ob[6] = {0.00, -0.03, 0.02, 0.06, 0.05, -0.04};
  const Eigen::Vector3d cs[6] = {{-1, 0, 0.5}, {1, 0, -2}, {0, -1, 1}, {0, 1, -0.5}, {-0.7, -0.7, 0.3}, {0.7, -0.7, 2}};
  WallRefinement wr(6);
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3d b(ub(rng), ub(rng), 0.2 * ub(rng));
    std::vector<WallRefinement::Observation> obs;
    for (int e = 0; e < 6; ++e) {
      const double t = ut(rng);
      obs.push_back({e, t, (1 - t) * oa[e] + t * ob[e] + cs[e].dot(b), cs[e]});
    }
    wr.add_scan(obs);
  }
  // The gauge: a registration error common to every scan moves each wall's offsets by c_e . delta, which the scans
  // cannot tell from the walls' own offsets (the prior picks the smallest). So the offsets come back up to one
  // delta: fitted here by least squares, the rest must vanish.
  auto residual_after_gauge = [&](const std::vector<RefinedSegment>& r, bool ends) {
    Eigen::MatrixXd C(2 * r.size(), 3);
    Eigen::VectorXd d(2 * r.size());
    for (size_t i = 0; i < r.size(); ++i) {
      const int e = r[i].element;
      const double ta = ends ? oa[e] : 0.5 * (oa[e] + ob[e]), tb = ends ? ob[e] : ta;
      C.row(2 * long(i)) = cs[e].transpose();
      C.row(2 * long(i) + 1) = cs[e].transpose();
      d[2 * long(i)] = r[i].offset_a - ta;
      d[2 * long(i) + 1] = r[i].offset_b - tb;
    }
    const Eigen::Vector3d delta = C.colPivHouseholderQr().solve(d);
    return (d - C * delta).cwiseAbs().maxCoeff();
  };
  const auto r = wr.result({0.01, 0.05, 3, true, 5});
  ASSERT_EQ(r.size(), 6u);
  for (const auto& s : r) EXPECT_EQ(s.frames, 400);
  EXPECT_LT(residual_after_gauge(r, true), 0.002);
  // Without the ends: each wall's mean offset at both ends.
  const auto m = wr.result({0.01, 0.05, 3, false, 5});
  ASSERT_EQ(m.size(), 6u);
  for (const auto& s : m) EXPECT_EQ(s.offset_a, s.offset_b);
  EXPECT_LT(residual_after_gauge(m, false), 0.002);
  // The ends differ where the walls' do (wall 3: 0.02 -> 0.06; wall 0: 0.04 -> 0.00), up to the gauge's share.
  EXPECT_GT(r[3].offset_b - r[3].offset_a, 0.03);
  EXPECT_LT(r[0].offset_b - r[0].offset_a, -0.03);
  // Too few scans for min_frames: nothing.
  EXPECT_TRUE(wr.result({0.01, 0.05, 3, true, 401}).empty());
}

TEST(WallRefinement, AScanOfFewerThanFourWallsAddsNothing) {
  WallRefinement wr(3);
  for (int k = 0; k < 20; ++k)
    wr.add_scan({{0, 0.5, 0.03, {1, 0, 0}}, {1, 0.5, 0.03, {0, 1, 0}}, {2, 0.5, 0.03, {0, 0, 1}}});
  EXPECT_TRUE(wr.result({0.01, 0.05, 3, true, 1}).empty());
}

}  // namespace
}  // namespace fploc::plandiff
