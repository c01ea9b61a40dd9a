#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fploc/laser2d/laser2d.h"

using namespace fploc;
using namespace fploc::laser2d;

namespace {
// A 360-beam scan over 360 degrees from (x0, y0, yaw0) inside the box [0, 8] x [0, 5] (ray casting).
PlanarScan box_scan(double x0, double y0, double yaw0, int n = 360) {
  PlanarScan s;
  s.utime = 1000;
  s.angle_min = float(-M_PI);
  s.angle_increment = float(2 * M_PI / n);
  s.time_increment = 0;
  s.range_min = 0.02f;
  s.range_max = 30.f;
  for (int i = 0; i < n; ++i) {
    const double a = yaw0 + s.angle_min + i * s.angle_increment, c = std::cos(a), d = std::sin(a);
    double t = 1e9;
    if (c > 1e-12) t = std::min(t, (8 - x0) / c);
    if (c < -1e-12) t = std::min(t, -x0 / c);
    if (d > 1e-12) t = std::min(t, (5 - y0) / d);
    if (d < -1e-12) t = std::min(t, -y0 / d);
    s.ranges.push_back(float(t));
  }
  return s;
}
double wall_distance(double x, double y) { return std::min({std::abs(x), std::abs(x - 8), std::abs(y), std::abs(y - 5)}); }
}  // namespace

TEST(Laser2d, FeaturesLieOnTheWalls) {
  const double x0 = 3, y0 = 2, yaw0 = 0.4;
  PlanarScan s = box_scan(x0, y0, yaw0);
  Laser2dConfig loam_only;
  loam_only.all_returns = false;
  Laser2dFeatures l2(loam_only);
  const auto& f = l2.process(s);
  EXPECT_EQ(f.status, FeatureStatus::kOk);
  EXPECT_EQ(l2.stats().returns, 360);
  ASSERT_GT(f.size(), 60u);
  int corners = 0, grouped = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    // Sensor frame -> world with the scan's pose.
    const double c = std::cos(yaw0), d = std::sin(yaw0);
    const double wx = x0 + c * f.points[k].p.x() - d * f.points[k].p.y(), wy = y0 + d * f.points[k].p.x() + c * f.points[k].p.y();
    EXPECT_LT(wall_distance(wx, wy), 1e-4);
    if (f.points[k].kind == FeatureKind::kCorner) {
      ++corners;
      // Corners of a box are only at its four corners.
      const double dc = std::min({std::hypot(wx, wy), std::hypot(wx - 8, wy), std::hypot(wx, wy - 5), std::hypot(wx - 8, wy - 5)});
      EXPECT_LT(dc, 0.6) << wx << " " << wy;
    }
    grouped += f.points[k].group >= 0;
  }
  EXPECT_GE(corners, 3);
  EXPECT_GT(grouped, int(f.size()) / 2);
  EXPECT_GE(f.num_groups, 4);
}

TEST(Laser2d, AllReturnsAfterTheLoamPicks) {
  PlanarScan s = box_scan(3, 2, 0.4);
  Laser2dConfig loam_only;
  loam_only.all_returns = false;
  Laser2dFeatures a(loam_only), b;
  const size_t picks = a.process(s).size();
  const auto& f = b.process(s);
  EXPECT_EQ(f.size(), 360u);
  const FeatureFrame fa = a.process(s);
  for (size_t k = 0; k < picks; ++k) EXPECT_TRUE(f.points[k].p == fa.points[k].p);
  for (size_t k = picks; k < f.size(); ++k) {
    EXPECT_EQ(f.points[k].group, -1);
    EXPECT_EQ(f.points[k].kind, FeatureKind::kSurface);
  }
}

TEST(Laser2d, DropsNonFiniteAndOutOfRange) {
  PlanarScan s = box_scan(3, 2, 0);
  s.ranges[10] = std::numeric_limits<float>::quiet_NaN();
  s.ranges[11] = std::numeric_limits<float>::infinity();
  s.ranges[12] = 0.01f;  // below range_min
  s.ranges[13] = 30.f;   // the maximum: no return
  Laser2dFeatures l2;
  l2.process(s);
  EXPECT_EQ(l2.stats().dropped_non_finite, 2);
  EXPECT_EQ(l2.stats().dropped_range, 2);
  EXPECT_EQ(l2.stats().returns, 356);
  for (size_t k = 0; k < l2.points().size(); ++k) EXPECT_NE(l2.points().column[k], 12);
}

TEST(Laser2d, BadGeometryAndMounting) {
  PlanarScan s = box_scan(3, 2, 0);
  s.angle_increment = std::numeric_limits<float>::quiet_NaN();
  Laser2dFeatures l2;
  EXPECT_EQ(l2.process(s).status, FeatureStatus::kBadInput);
  PlanarScan empty;
  EXPECT_EQ(l2.process(empty).status, FeatureStatus::kBadInput);
  // A laser mounted 0.2 m ahead, turned 90 degrees: points come out in the robot frame.
  Laser2dConfig c;
  c.mount_x_m = 0.2;
  c.mount_yaw_rad = M_PI / 2;
  Laser2dFeatures m(c);
  PlanarScan one = box_scan(3, 2, 0);
  m.process(one);
  // Beam at angle 0 (index 180) hits x = 8 at 5 m: robot frame (0.2, 5).
  for (size_t k = 0; k < m.points().size(); ++k)
    if (m.points().column[k] == 180) {
      EXPECT_NEAR(m.points().x[k], 0.2, 1e-5);
      EXPECT_NEAR(m.points().y[k], 5.0, 1e-5);
    }
}
