#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <algorithm>
#include <map>

#include "fploc/core/rng.h"
#include "fploc/eval/asbuilt_bound.h"

using namespace fploc;
using namespace fploc::eval;
using V2 = Eigen::Vector2d;

namespace {

// A 6 x 4 m room (corners joined) with a 0.6 m partition wall standing free and a round pillar.
FloorPlan room() {
  FloorPlan p;
  const V2 c[4] = {{0, 0}, {6, 0}, {6, 4}, {0, 4}};
  for (int i = 0; i < 4; ++i) p.elements.push_back(Element::segment(c[i], c[(i + 1) % 4]));
  p.elements.push_back(Element::segment({4.5, 1.0}, {4.5, 1.6}));
  p.elements.push_back(Element::circle({1.5, 2.8}, 0.2));
  return p;
}

int count_of(const Element& e, const Eigen::Vector3d& pose) {
  if (e.kind != ElementKind::kSegment) return 8;
  const V2 da = e.a - pose.head<2>(), db = e.b - pose.head<2>();
  return std::max(4, int(std::abs(std::atan2(da.x() * db.y() - da.y() * db.x(), da.dot(db))) / 0.02));
}

// Points on the world's elements (the plan with each joint / pillar centre displaced), seen from `pose`, in
// the sensor frame: as a scanner sees them, one per 0.02 rad a segment spans (a near wall holds more of them than a
// far one), 8 per pillar (on the side facing the sensor).
std::vector<V2> scan_of(const FloorPlan& plan, const std::map<std::pair<long, long>, V2>& joint_disp,
                        const std::vector<V2>& pillar_disp, const Eigen::Vector3d& pose) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  auto to_sensor = [&](const V2& w) {
    const V2 d = w - pose.head<2>();
    return V2(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  };
  auto key = [](const V2& p) { return std::make_pair(std::lround(p.x() * 1000), std::lround(p.y() * 1000)); };
  std::vector<V2> pts;
  size_t k = 0;
  for (const Element& e : plan.elements) {
    if (e.kind == ElementKind::kSegment) {
      const V2 a = e.a + joint_disp.at(key(e.a)), b = e.b + joint_disp.at(key(e.b));
      const int n = count_of(e, pose);
      for (int i = 0; i < n; ++i) pts.push_back(to_sensor(a + (i + 0.5) / n * (b - a)));
    } else {
      const V2 cc = e.c + pillar_disp[k++];
      const V2 toward = (pose.head<2>() - e.c).normalized();
      const double a0 = std::atan2(toward.y(), toward.x());
      for (int i = 0; i < 8; ++i) {
        const double a = a0 + (i - 3.5) * 0.15;
        pts.push_back(to_sensor(cc + e.r * V2(std::cos(a), std::sin(a))));
      }
    }
  }
  return pts;
}

}  // namespace

// The bound is the error covariance of the best estimator: drawing worlds from the model and estimating each
// scan's pose with the displacements as unknowns under their prior (solved here directly, as one stacked least
// squares problem against the plan) gives errors whose covariance is the bound's, while fitting the points to
// the plan alone (what a localizer unaware of the offsets does) is worse.
TEST(AsBuiltBound, IsTheErrorCovarianceOfTheBestEstimatorOverWorldsDrawnFromTheModel) {
  const FloorPlan plan = room();
  const double sigma = 0.03, sp = 0.005;
  const Eigen::Vector3d pose(2.2, 1.7, 0.4);
  AsBuiltBoundOptions o;
  o.vertex_sigma_m = sigma;
  o.point_sigma_m = sp;
  // The bound from the plan's own points (its geometry does not depend on the small displacements).
  std::map<std::pair<long, long>, V2> zero;
  for (const Element& e : plan.elements)
    if (e.kind == ElementKind::kSegment)
      for (const V2& v : {e.a, e.b}) zero[{std::lround(v.x() * 1000), std::lround(v.y() * 1000)}] = V2::Zero();
  const ScanBound b = asbuilt_scan_bound(plan, pose, scan_of(plan, zero, {V2::Zero()}, pose), o);
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(b.elements, 6);
  int expected_points = 0;
  for (const Element& e : plan.elements) expected_points += count_of(e, pose);
  EXPECT_EQ(b.points, expected_points);

  Rng rng(7);
  Eigen::Matrix3d best_cov = Eigen::Matrix3d::Zero(), plain_cov = Eigen::Matrix3d::Zero();
  const int draws = 3000;
  for (int k = 0; k < draws; ++k) {
    std::map<std::pair<long, long>, V2> jd = zero;
    for (auto& [key, d] : jd) d = V2(rng.normal(sigma), rng.normal(sigma));
    const std::vector<V2> pd = {V2(rng.normal(sigma), rng.normal(sigma))};
    std::vector<V2> pts = scan_of(plan, jd, pd, pose);
    for (V2& q : pts) q += V2(rng.normal(sp), rng.normal(sp));
    // Unknowns: pose correction (3), then each joint's and the pillar's displacement (2 each), in a fixed order.
    std::map<std::pair<long, long>, int> col;
    for (auto& [key, d] : jd) col.emplace(key, 3 + 2 * int(col.size()));
    const int pillar_col = 3 + 2 * int(col.size()), n = pillar_col + 2;
    Eigen::MatrixXd J(int(pts.size()) + n - 3, n);
    Eigen::VectorXd r(J.rows());
    J.setZero();
    const double c = std::cos(pose.z()), s = std::sin(pose.z());
    int row = 0;
    size_t pi = 0;
    for (const Element& e : plan.elements) {
      const int count = count_of(e, pose);
      for (int i = 0; i < count; ++i, ++pi, ++row) {
        const V2 w = pose.head<2>() + V2(c * pts[pi].x() - s * pts[pi].y(), s * pts[pi].x() + c * pts[pi].y());
        V2 nrm;
        double res;
        if (e.kind == ElementKind::kSegment) {
          const V2 ab = e.b - e.a;
          nrm = V2(-ab.y(), ab.x()).normalized();
          const double t = std::clamp((w - e.a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
          res = nrm.dot(w - e.a);
          J.block<1, 2>(row, col.at({std::lround(e.a.x() * 1000), std::lround(e.a.y() * 1000)})) = -(1 - t) * nrm.transpose();
          J.block<1, 2>(row, col.at({std::lround(e.b.x() * 1000), std::lround(e.b.y() * 1000)})) = -t * nrm.transpose();
        } else {
          nrm = (w - e.c).normalized();
          res = (w - e.c).norm() - e.r;
          J.block<1, 2>(row, pillar_col) = -nrm.transpose();
        }
        const V2 rel = w - pose.head<2>();
        J.block<1, 3>(row, 0) << nrm.x(), nrm.y(), -nrm.x() * rel.y() + nrm.y() * rel.x();
        r(row) = res;
      }
    }
    J.topRows(row) /= sp;
    r.head(row) /= sp;
    J.bottomRightCorner(n - 3, n - 3) = Eigen::MatrixXd::Identity(n - 3, n - 3) / sigma;  // the prior
    r.tail(n - 3).setZero();
    const Eigen::VectorXd x = -J.colPivHouseholderQr().solve(r);
    const Eigen::Vector3d xp = -J.topLeftCorner(row, 3).colPivHouseholderQr().solve(r.head(row));
    best_cov += x.head<3>() * x.head<3>().transpose() / draws;
    plain_cov += xp * xp.transpose() / draws;
  }
  // 3000 draws: a variance is known to ~2.6 % (1 sigma); 10 % is four of those.
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(best_cov(i, i) / b.cov(i, i), 1.0, 0.10) << "component " << i;
  EXPECT_NEAR(best_cov(0, 1) / std::sqrt(best_cov(0, 0) * best_cov(1, 1)),
              b.cov(0, 1) / std::sqrt(b.cov(0, 0) * b.cov(1, 1)), 0.06);
  EXPECT_GT(plain_cov(0, 0) + plain_cov(1, 1), 1.2 * (b.cov(0, 0) + b.cov(1, 1)));
}

// Two long parallel walls: across the corridor the walls' offsets bound the error, along it nothing does.
TEST(AsBuiltBound, ALongCorridorLeavesItsAxisOpen) {
  FloorPlan p;
  p.elements.push_back(Element::segment({-50, -1.2}, {50, -1.2}));
  p.elements.push_back(Element::segment({50, 1.2}, {-50, 1.2}));
  std::vector<V2> pts;
  for (int i = -40; i <= 40; ++i) pts.push_back({0.1 * i, -1.2}), pts.push_back({0.1 * i, 1.2});
  EXPECT_FALSE(asbuilt_scan_bound(p, Eigen::Vector3d::Zero(), pts).ok());
  // Closed at both ends 5 m away (own joints): bounded; across, each wall's offset mid-way has variance sigma^2 / 2,
  // the two averaged sigma^2 / 4: the lateral sigma is sigma / 2.
  p.elements.push_back(Element::segment({5, -1.2}, {5, 1.2}));
  p.elements.push_back(Element::segment({-5, 1.2}, {-5, -1.2}));
  for (int i = -10; i <= 10; ++i) pts.push_back({5, 0.1 * i}), pts.push_back({-5, 0.1 * i});
  AsBuiltBoundOptions o;
  o.vertex_sigma_m = 0.02;
  o.point_sigma_m = 1e-4;
  const ScanBound b = asbuilt_scan_bound(p, Eigen::Vector3d::Zero(), pts, o);
  ASSERT_TRUE(b.ok());
  EXPECT_NEAR(std::sqrt(b.cov(1, 1)), 0.01, 0.0015);
}

// The bound scales with sigma (the points' noise aside); points off every element (clutter, people) are left out;
// bad options are refused.
TEST(AsBuiltBound, ScalesWithSigmaAndIgnoresClutter) {
  const FloorPlan plan = room();
  const Eigen::Vector3d pose(2.2, 1.7, 0.4);
  std::map<std::pair<long, long>, V2> zero;
  for (const Element& e : plan.elements)
    if (e.kind == ElementKind::kSegment)
      for (const V2& v : {e.a, e.b}) zero[{std::lround(v.x() * 1000), std::lround(v.y() * 1000)}] = V2::Zero();
  std::vector<V2> pts = scan_of(plan, zero, {V2::Zero()}, pose);
  AsBuiltBoundOptions o;
  o.point_sigma_m = 1e-5;
  o.vertex_sigma_m = 0.02;
  const ScanBound b2 = asbuilt_scan_bound(plan, pose, pts, o);
  o.vertex_sigma_m = 0.05;
  const ScanBound b5 = asbuilt_scan_bound(plan, pose, pts, o);
  EXPECT_NEAR(b5.xy_rms_m() / b2.xy_rms_m(), 2.5, 0.01);
  pts.push_back({0.3, 0.2});  // 0.3 m from the sensor: far from every wall (the pose is 1.7 m from the nearest)
  pts.push_back({std::nan(""), 1.0});
  const ScanBound bc = asbuilt_scan_bound(plan, pose, pts, o);
  EXPECT_EQ(bc.points, b5.points);
  EXPECT_NEAR(bc.xy_rms_m(), b5.xy_rms_m(), 1e-12);
  o.vertex_sigma_m = 0;
  EXPECT_THROW(asbuilt_scan_bound(plan, pose, pts, o), std::invalid_argument);
}

// A window of scans whose relative poses are exact shares one pose error and the walls' displacements: the same scan
// twice tells nothing new about the walls (the bound barely moves, where two independent looks would divide the
// variance by two); a second place can only add (in this room it sees the same walls: little); the error at another
// scan of the window is the same rigid error carried over there.
TEST(AsBuiltBound, AWindowSharesThePoseErrorAndTheWalls) {
  const FloorPlan plan = room();
  std::map<std::pair<long, long>, V2> zero;
  for (const Element& e : plan.elements)
    if (e.kind == ElementKind::kSegment)
      for (const V2& v : {e.a, e.b}) zero[{std::lround(v.x() * 1000), std::lround(v.y() * 1000)}] = V2::Zero();
  AsBuiltBoundOptions o;
  o.point_sigma_m = 1e-3;
  const Eigen::Vector3d pa(2.2, 1.7, 0.4), pb(4.0, 2.9, -1.0);
  AsBuiltBound b(plan, o);
  const int a0 = b.add_scan(pa, scan_of(plan, zero, {V2::Zero()}, pa));
  const int a1 = b.add_scan(pa, scan_of(plan, zero, {V2::Zero()}, pa));
  const int b0 = b.add_scan(pb, scan_of(plan, zero, {V2::Zero()}, pb));
  const ScanBound one = b.bound(a0), twice = b.bound(a0, a1, a0);
  EXPECT_NEAR(one.xy_rms_m(), asbuilt_scan_bound(plan, pa, scan_of(plan, zero, {V2::Zero()}, pa), o).xy_rms_m(), 1e-12);
  EXPECT_LT(twice.xy_rms_m(), one.xy_rms_m());
  EXPECT_GT(twice.xy_rms_m(), 0.99 * one.xy_rms_m());
  const ScanBound both = b.bound(a0, b0, a0);
  EXPECT_LE(both.cov(0, 0), one.cov(0, 0) * (1 + 1e-9));
  EXPECT_LE(both.cov(1, 1), one.cov(1, 1) * (1 + 1e-9));
  EXPECT_EQ(both.points, 2 * one.points + b.bound(b0).points);
  // At b0's position: the same rigid error, moved by its rotation about a0.
  const ScanBound at_b = b.bound(a0, b0, b0);
  const V2 d = pb.head<2>() - pa.head<2>();
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity();
  T(0, 2) = -d.y();
  T(1, 2) = d.x();
  const Eigen::Matrix3d moved = T * both.cov * T.transpose();
  EXPECT_LT((moved - at_b.cov).norm(), 1e-9 * moved.norm());
  EXPECT_THROW(b.bound(0, 3, 0), std::out_of_range);
}
