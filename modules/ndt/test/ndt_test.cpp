#include <gtest/gtest.h>

#include <cmath>
#include <Eigen/Eigenvalues>
#include <limits>

#include "fploc/ndt/ndt_localizer.h"
#include "fploc/ndt/plan_cloud.h"
#include "fploc/sim/scenarios.h"

using namespace fploc;
using namespace fploc::ndt;

namespace {

// A 16-ring scan of the plan's segments from pose (x, y, yaw) at height h: 2D ray casting per bearing,
// rings at -15..15 deg kept between the floor and 3 m. Sensor frame points.
Scan cast_scan(const FloorPlan& plan, double x, double y, double yaw, double h, double t = 0) {
  Scan s;
  s.t = t;
  s.z = h;
  for (int b = 0; b < 720; ++b) {
    const double a = yaw + b * M_PI / 360;
    const Eigen::Vector2d o(x, y), d(std::cos(a), std::sin(a));
    double best = std::numeric_limits<double>::infinity();
    for (const auto& e : plan.elements) {
      if (e.kind != ElementKind::kSegment) continue;
      const Eigen::Vector2d u = e.b - e.a;
      const double den = d.x() * u.y() - d.y() * u.x();
      if (std::abs(den) < 1e-12) continue;
      const Eigen::Vector2d w = e.a - o;
      const double t1 = (w.x() * u.y() - w.y() * u.x()) / den, t2 = (w.x() * d.y() - w.y() * d.x()) / den;
      if (t1 > 0.3 && t2 >= 0 && t2 <= 1) best = std::min(best, t1);
    }
    if (!std::isfinite(best) || best > 40) continue;
    for (int ring = 0; ring < 16; ++ring) {
      const double el = (-15.0 + 2.0 * ring) * M_PI / 180;
      const double zw = h + best * std::tan(el);
      if (zw < 0.05 || zw > 2.95) continue;
      const double bl = b * M_PI / 360;
      s.points.emplace_back(float(best * std::cos(bl)), float(best * std::sin(bl)), float(zw - h));
    }
  }
  return s;
}

FloorPlan corridor(double length, double width) {
  FloorPlan p;
  p.elements.push_back(Element::segment({0, 0}, {length, 0}));
  p.elements.push_back(Element::segment({0, width}, {length, width}));
  return p;
}

}  // namespace

TEST(PlanCloud, ExtrudesSegmentsAndCircles) {
  FloorPlan p;
  p.elements.push_back(Element::segment({0, 0}, {1, 0}));
  PlanCloudOptions o;
  o.z_min_m = 0;
  o.z_max_m = 1;
  o.spacing_m = 0.1;
  auto pts = plan_cloud(p, o);
  EXPECT_EQ(pts.size(), 11u * 11u);
  for (const auto& q : pts) {
    EXPECT_NEAR(q.y(), 0.0, 1e-6);
    EXPECT_GE(q.z(), -1e-6);
    EXPECT_LE(q.z(), 1 + 1e-6);
  }
  p.elements.push_back(Element::circle({5, 5}, 0.5));
  pts = plan_cloud(p, o);
  size_t on_circle = 0;
  for (const auto& q : pts)
    if ((q.head<2>() - Eigen::Vector2f(5, 5)).norm() < 1.0f) {
      EXPECT_NEAR((q.head<2>() - Eigen::Vector2f(5, 5)).norm(), 0.5, 1e-5);
      ++on_circle;
    }
  EXPECT_GE(on_circle, 31u * 11u);  // 2 pi r / 0.1 = 31.4 -> 32 points per height
  o.spacing_m = 0;
  EXPECT_THROW(plan_cloud(p, o), std::invalid_argument);
  o.spacing_m = 0.1;
  o.z_max_m = 0;
  EXPECT_THROW(plan_cloud(p, o), std::invalid_argument);
}

TEST(NdtLocalizer, ConvergesInTheRoomFromAnOffsetPrediction) {
  const FloorPlan plan = sim::demo_room_plan();
  Localizer loc(plan);
  EXPECT_GT(loc.map_points(), 10000u);
  const double x = 5.8, y = 3.2, yaw = -1.44;
  Result r = loc.process(cast_scan(plan, x, y, yaw, 1.0));
  EXPECT_EQ(r.status, Status::kNotInitialised);
  loc.set_pose(x + 0.25, y - 0.2, yaw + 0.08);
  r = loc.process(cast_scan(plan, x, y, yaw, 1.0, 0.1));
  EXPECT_EQ(r.status, Status::kOk) << r.text;
  EXPECT_TRUE(r.matched && r.converged);
  EXPECT_NEAR(r.x, x, 0.03);
  EXPECT_NEAR(r.y, y, 0.03);
  EXPECT_NEAR(r.yaw, yaw, 0.01);
  EXPECT_GT(r.inlier_ratio, 0.9);
  // The covariance is a positive definite matrix of small, finite sigmas.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(r.covariance);
  EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
  EXPECT_LT(std::sqrt(r.covariance(0, 0)), 0.1);
  EXPECT_LT(std::sqrt(r.covariance(2, 2)), 0.05);
  // Next scan after moving 0.1 m: the constant-velocity prediction and the IMU yaw keep it locked.
  r = loc.process(cast_scan(plan, x + 0.05, y - 0.08, yaw + 0.02, 1.0, 0.2), 0.02);
  EXPECT_EQ(r.status, Status::kOk) << r.text;
  EXPECT_NEAR(r.x, x + 0.05, 0.03);
  EXPECT_NEAR(r.y, y - 0.08, 0.03);
}

// Two long parallel walls fix y and yaw but not x: the covariance is much larger along the corridor.
TEST(NdtLocalizer, CovarianceGrowsAlongAFeaturelessCorridor) {
  const FloorPlan plan = corridor(60, 3);
  Localizer loc(plan);
  loc.set_pose(30, 1.5, 0.0);
  const Result r = loc.process(cast_scan(plan, 30, 1.5, 0.0, 1.0, 0.1));
  ASSERT_TRUE(r.matched) << r.text;
  EXPECT_NEAR(r.y, 1.5, 0.03);
  EXPECT_GT(r.covariance(0, 0), 10 * r.covariance(1, 1));
}

TEST(NdtLocalizer, UnusableScanKeepsThePredictionAndEndsLost) {
  const FloorPlan plan = sim::demo_room_plan();
  Config c;
  c.lost_after = 3;
  Localizer loc(plan, c);
  loc.set_pose(5.8, 3.2, -1.44);
  Scan empty;
  Result r;
  for (int i = 1; i <= 3; ++i) {
    empty.t = 0.1 * i;
    r = loc.process(empty);
    EXPECT_FALSE(r.matched);
    EXPECT_NEAR(r.x, 5.8, 1e-9);
  }
  EXPECT_EQ(r.status, Status::kLost);
  EXPECT_GE(r.covariance(0, 0), 1.0);
}

// A match 0.09 m from the last pose 0.02 s later is 4.7 m/s; the prediction flies on at the platform's top speed
// (max_speed_mps, 2 m/s) at most while the next scans are unusable.
TEST(NdtLocalizer, PredictionSpeedIsThePlatformsAtMost) {
  const FloorPlan plan = sim::demo_room_plan();
  Localizer loc(plan);
  const double x = 5.8, y = 3.2, yaw = -1.44;
  loc.set_pose(x, y, yaw);
  Result r = loc.process(cast_scan(plan, x, y, yaw, 1.0, 0.1));
  ASSERT_TRUE(r.matched) << r.text;
  const double x0 = r.x, y0 = r.y;
  r = loc.process(cast_scan(plan, x + 0.05, y - 0.08, yaw, 1.0, 0.12));
  ASSERT_TRUE(r.matched) << r.text;
  ASSERT_GT(std::hypot(r.x - x0, r.y - y0), 0.06);  // > 3 m/s
  const double x1 = r.x, y1 = r.y;
  Scan empty;
  empty.t = 0.14;
  r = loc.process(empty);
  EXPECT_FALSE(r.matched);
  EXPECT_NEAR(std::hypot(r.x - x1, r.y - y1), 0.04, 0.002);  // 2 m/s for 0.02 s
}

TEST(NdtLocalizer, BadConfigIsRejected) {
  Config c;
  c.resolution_m = 0;
  EXPECT_THROW(Localizer(sim::demo_room_plan(), c), std::invalid_argument);
  c = Config{};
  c.outlier_ratio = 1.5;
  EXPECT_THROW(Localizer(sim::demo_room_plan(), c), std::invalid_argument);
}
