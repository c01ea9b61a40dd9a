#include <gtest/gtest.h>

#include <random>

#include "fploc/floorplan/plan.h"

using namespace fploc;

TEST(Plan, ClosestPointSegmentCircleArc) {
  auto s = Element::segment({0, 0}, {2, 0});
  EXPECT_NEAR(distance(s, {1, 1}), 1.0, 1e-12);
  EXPECT_NEAR(distance(s, {3, 0}), 1.0, 1e-12);
  auto c = Element::circle({0, 0}, 1.0);
  EXPECT_NEAR(distance(c, {3, 0}), 2.0, 1e-12);
  EXPECT_NEAR(distance(c, {0.5, 0}), 0.5, 1e-12);
  auto a = Element::arc({0, 0}, 1.0, 0, M_PI / 2);  // first quadrant
  EXPECT_NEAR(distance(a, {2, 2}), std::sqrt(8.0) - 1.0, 1e-12);
  EXPECT_NEAR(distance(a, {-2, 0}), std::sqrt(5.0), 1e-12);  // nearest end (0,1)
}

// min_distance/max_distance must bracket the true distance of every point in the box.
TEST(Plan, BoxDistanceBoundsAreValid) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-3, 3);
  std::vector<Element> els = {Element::segment({-1, -2}, {2, 1}), Element::circle({0.5, 0.2}, 0.7),
                              Element::arc({0, 0}, 1.5, 0.3, 2.0), Element::arc({1, -1}, 0.8, 5.0, 7.5)};
  for (int trial = 0; trial < 300; ++trial) {
    Box2 b;
    b.min = {U(rng), U(rng)};
    b.max = b.min + Eigen::Vector2d(std::abs(U(rng)) * 0.5, std::abs(U(rng)) * 0.5);
    for (const auto& e : els) {
      const double lo = min_distance(e, b), hi = max_distance(e, b);
      for (int k = 0; k < 50; ++k) {
        std::uniform_real_distribution<double> ux(b.min.x(), b.max.x()), uy(b.min.y(), b.max.y());
        const double d = distance(e, {ux(rng), uy(rng)});
        EXPECT_LE(lo, d + 1e-9);
        EXPECT_GE(hi, d - 1e-9);
      }
    }
  }
}
