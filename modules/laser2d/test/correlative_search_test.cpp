// The branch-and-bound correlative search returns the exhaustive search's best candidate (the pyramid's bounds
// are upper bounds), on a synthetic room, for windows with and without the prior, and keeps distinct candidates.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fploc/laser2d/correlative_search.h"
#include "fploc/laser2d/grid_localizer.h"
#include "synthetic_grid.h"

namespace {

using fploc::OccupancyGrid;
using fploc::Pose2;
namespace l2 = fploc::laser2d;

OccupancyGrid room() {
  OccupancyGrid g = l2::test::blank_grid(240, 160);
  auto occ = [&](double x, double y) { l2::test::occupy(g, x, y); };
  for (double t = -0.5; t <= 10.5; t += 0.02) occ(t, -0.5), occ(t, 6.5);
  for (double t = -0.5; t <= 6.5; t += 0.02) occ(-0.5, t), occ(10.5, t);
  for (double t = 2.0; t <= 6.5; t += 0.02) occ(4.0, t);
  for (double t = 6.0; t <= 9.0; t += 0.02) occ(t, 2.0);
  return g;
}

// Returns of a 180-degree scan from p (wall points within 12 m in the half-plane ahead), in the robot frame.
std::vector<Eigen::Vector2d> scan_of(const OccupancyGrid& g, const Pose2& p, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.01);
  std::vector<Eigen::Vector2d> out;
  for (int k = 0; k < 181; k += 2) {
    const double a = p.yaw - M_PI / 2 + k * M_PI / 180;
    const double d = l2::test::first_hit(g, p.x, p.y, a, 12);
    if (std::isfinite(d)) {
      const double r = d + n(rng), b = a - p.yaw;
      out.emplace_back(r * std::cos(b), r * std::sin(b));
    }
  }
  return out;
}

TEST(CorrelativeSearch, BranchAndBoundFindsTheExhaustiveBest) {
  const OccupancyGrid g = room();
  const fploc::DistanceField df(g, 1.0);
  const l2::ScorePyramid pyr(df, 0.1);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(1, 9), uy(0.5, 5.5), uyaw(-M_PI, M_PI), uoff(-0.4, 0.4);
  for (int trial = 0; trial < 12; ++trial) {
    const Pose2 truth{ux(rng), uy(rng), uyaw(rng)};
    const auto pts = scan_of(g, truth, rng);
    ASSERT_GT(pts.size(), 20u);
    l2::SearchWindow w;
    w.center = {truth.x + uoff(rng), truth.y + uoff(rng), truth.yaw + 0.3 * uoff(rng)};
    w.xy_m = trial % 2 ? 0.6 : 1.3;
    w.yaw_rad = 8 * M_PI / 180;
    w.sigma_xy_m = 0.3;
    w.sigma_yaw_rad = 0.1;
    w.prior_kappa = trial % 3 == 0 ? 0 : 1.5;
    const l2::SearchCandidate ex = l2::correlative_search_exhaustive(df, pyr, pts, w);
    l2::SearchStats st;
    const auto bb = l2::correlative_search(df, pyr, pts, w, l2::SearchOptions{}, &st);
    ASSERT_EQ(bb.size(), 1u);
    EXPECT_NEAR(bb[0].score, ex.score, 1e-9) << "trial " << trial;
    // Far fewer exact evaluations than the exhaustive search's (2 * 12 + 1)^2 .. (2 * 26 + 1)^2 per yaw.
    const long full = long(std::pow(2 * std::ceil(w.xy_m / 0.05) + 1, 2)) * 17;
    EXPECT_LT(st.leaves, full / 4) << "trial " << trial;
  }
}

TEST(CorrelativeSearch, KeepsDistinctCandidatesBestFirst) {
  const OccupancyGrid g = room();
  const fploc::DistanceField df(g, 1.0);
  const l2::ScorePyramid pyr(df, 0.1);
  std::mt19937 rng(5);
  const Pose2 truth{2.0, 3.0, 0.3};
  const auto pts = scan_of(g, truth, rng);
  l2::SearchWindow w;
  w.center = truth;
  w.xy_m = 1.5;
  w.yaw_rad = 20 * M_PI / 180;
  w.prior_kappa = 0;
  l2::SearchOptions o;
  o.keep = 4;
  const auto c = l2::correlative_search(df, pyr, pts, w, o);
  ASSERT_GE(c.size(), 2u);
  EXPECT_LT(std::hypot(c[0].pose.x - truth.x, c[0].pose.y - truth.y), 0.06);
  for (size_t a = 0; a < c.size(); ++a) {
    if (a > 0) {
      EXPECT_LE(c[a].score, c[a - 1].score);
    }
    for (size_t b = a + 1; b < c.size(); ++b)
      EXPECT_TRUE(std::hypot(c[a].pose.x - c[b].pose.x, c[a].pose.y - c[b].pose.y) >= o.sep_xy_m ||
                  std::abs(fploc::wrap_angle(c[a].pose.yaw - c[b].pose.yaw)) >= o.sep_yaw_rad);
  }
}

}  // namespace
