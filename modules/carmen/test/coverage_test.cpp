// The split rule of the non-circular protocol: which scans a prefix's map covers (modules/carmen/coverage.h).
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/carmen/coverage.h"

using namespace fploc::carmen;

namespace {

// A 180-beam scan from inside the box [x0, x0 + 6] x [0, 4] at (x, y, theta).
LaserRecord scan_in_box(double x0, double x, double y, double theta) {
  LaserRecord r;
  r.pose = {x, y, theta};
  for (int i = 0; i < 180; ++i) {
    const double a = theta - M_PI / 2 + i * M_PI / 180, c = std::cos(a), s = std::sin(a);
    double t = 1e9;
    if (c > 1e-9) t = std::min(t, (x0 + 6 - x) / c);
    if (c < -1e-9) t = std::min(t, (x0 - x) / c);
    if (s > 1e-9) t = std::min(t, (4 - y) / s);
    if (s < -1e-9) t = std::min(t, -y / s);
    r.ranges.push_back(float(t));
  }
  return r;
}

// Scans 0-9 in room A, 10-19 each in a room of its own (never seen before or after), 20-29 in room A again.
std::vector<LaserRecord> three_parts() {
  std::vector<LaserRecord> s;
  for (int k = 0; k < 10; ++k) s.push_back(scan_in_box(0, 2 + 0.2 * k, 2, k * M_PI / 5));
  for (int k = 0; k < 10; ++k) s.push_back(scan_in_box(20 + 10 * k, 23 + 10 * k, 2, 0.3 * k));
  for (int k = 0; k < 10; ++k) s.push_back(scan_in_box(0, 3.7 - 0.15 * k, 1.5, 0.5 + k * M_PI / 5));
  return s;
}

}  // namespace

TEST(Coverage, PrefixCoverageOfRevisitsAndNewRooms) {
  const auto scans = three_parts();
  const auto fc = prefix_coverage(scans, CoverageConfig{});
  ASSERT_EQ(fc.size(), 30u);
  // A room of its own is covered only by a prefix that contains the scan itself.
  for (int k = 10; k < 20; ++k) EXPECT_EQ(fc[size_t(k)], size_t(k + 1)) << k;
  // The revisits of room A: covered by the first part's scans.
  for (int k = 20; k < 30; ++k) EXPECT_LE(fc[size_t(k)], 10u) << k;
}

TEST(Coverage, SplitRuleTakesTheSmallestPrefixThatCoversTheRest) {
  const auto fc = prefix_coverage(three_parts(), CoverageConfig{});
  SplitRule rule;  // candidates 0.20, 0.25, ... 0.80 of 30 scans
  rule.covered_share = 0.9;
  Split s = choose_split(fc, rule);
  // S = 18 (0.60): 10 of the 12 remaining covered (0.83); S = 20 (0.65, rounded 19.5 -> 20): all 10.
  EXPECT_TRUE(s.met);
  EXPECT_EQ(s.split, 20u);
  EXPECT_NEAR(s.covered_share, 1.0, 1e-12);
  // Not reachable below 0.60: the best candidate, marked not met.
  rule.max_fraction = 0.6;
  s = choose_split(fc, rule);
  EXPECT_FALSE(s.met);
  EXPECT_EQ(s.split, 18u);
  EXPECT_NEAR(s.covered_share, 10.0 / 12.0, 1e-12);
  EXPECT_THROW(choose_split({1}, rule), std::invalid_argument);
}

TEST(Coverage, GridCoverageOfTheMapOfAPrefix) {
  const auto scans = three_parts();
  std::vector<const LaserRecord*> first;
  for (size_t k = 0; k < 10; ++k) first.push_back(&scans[k]);
  GridConfig gc;
  gc.min_hits = 1;
  gc.occupied_ratio = 0.1;
  gc.hit_clearance_m = 0.1;
  const Grid g = build_grid(first, gc);
  const auto cov = grid_coverage(g, scans, 10, 30, CoverageConfig{});
  ASSERT_EQ(cov.size(), 20u);
  for (int k = 0; k < 10; ++k) EXPECT_LT(cov[size_t(k)], 0.05) << "own room " << k;
  for (int k = 10; k < 20; ++k) EXPECT_GT(cov[size_t(k)], 0.9) << "room A again " << k;
}
