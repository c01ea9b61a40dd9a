// DrawingScale on its own model (plan_diff_test runs it inside PlanDiff on simulated scans).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fploc/plandiff/drawing_scale.h"

namespace fploc::plandiff {
namespace {

// Scans of four walls (normals +-x, +-y) whose points follow off = s * dd + n . b + noise, with a large
// registration bias b of its own per scan: the bias is eliminated per scan, the scale comes back.
DrawingScale::Estimate scale_of(double s, double noise, int scans, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-4.0, 4.0), ub(-0.3, 0.3);
  std::normal_distribution<double> g(0.0, noise);
  const Eigen::Vector2d normals[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  DrawingScale ds(4);
  for (int k = 0; k < scans; ++k) {
    const Eigen::Vector2d b(ub(rng), ub(rng));
    for (int i = 0; i < 200; ++i) {
      const int e = i % 4;
      const Eigen::Vector2d& n = normals[e];
      const double dd = std::abs(u(rng)) + 0.5;
      ds.add_point(e, Eigen::Vector3d(dd, n.x(), n.y()), s * dd + n.dot(b) + g(rng));
    }
    ds.end_scan();
  }
  return ds.estimate(scans, 5);
}

TEST(DrawingScale, TheScaleComesBackWithEachScansBiasEliminated) {
  const auto e = scale_of(0.005, 0.01, 40, 1);
  EXPECT_NEAR(e.error, 0.005, 0.001);
  EXPECT_GT(e.sigma, 0.0);
  EXPECT_LT(e.sigma, 0.002);
  EXPECT_EQ(e.points, 40 * (200 - 2));
  const auto z = scale_of(0.0, 0.01, 40, 2);
  EXPECT_LT(std::abs(z.error), 4 * z.sigma) << "drawn to scale: " << z.error << " +- " << z.sigma;
}

TEST(DrawingScale, TooLittleIsNoEstimate) {
  DrawingScale ds(4);
  for (int i = 0; i < 19; ++i) ds.add_point(i % 4, Eigen::Vector3d(1.0 + i, i % 2, (i + 1) % 2), 0.01);
  ds.end_scan();  // fewer than 20 points in the scan: nothing
  const auto e = ds.estimate(1, 5);
  EXPECT_EQ(e.points, 0);
  EXPECT_EQ(e.error, 0.0);
  EXPECT_EQ(e.sigma, 0.0);
}

}  // namespace
}  // namespace fploc::plandiff
