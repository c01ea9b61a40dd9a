// The per-element point budget (AssignOptions::element_quota): a wall seen with a handful of points keeps
// them all when the frame is thinned to every stride-th point, and their sampling weight keeps the frame's
// cost an estimate of the cost over all points.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "fploc/matcher/map.h"
#include "fploc/matcher/plan_terms.h"

using namespace fploc;
using namespace fploc::matcher;

namespace {

// Two long walls 4 m apart (y = 0, y = 4) and a short wall across them (x = 8): 400 points on each long
// wall, 12 on the short one (the only wall that holds the position along the corridor).
struct Scene {
  FloorPlan plan;
  FeatureFrame f;
  std::vector<int> wall_of;  // per point: 0, 1 (long walls), 2 (the short one)
};

Scene scene(bool groups) {
  Scene s;
  s.plan.elements.push_back(Element::segment({-10, 0}, {10, 0}));
  s.plan.elements.push_back(Element::segment({-10, 4}, {10, 4}));
  s.plan.elements.push_back(Element::segment({8, 0}, {8, 4}));
  auto add = [&](double x, double y, int wall) {
    Feature2 p;
    p.p = Eigen::Vector2d(x, y);
    p.group = groups ? wall : -1;
    s.f.points.push_back(p);
    s.wall_of.push_back(wall);
  };
  // Interleaved as a scan sweeps: the short wall's points come in one run between the long walls'.
  for (int i = 0; i < 400; ++i) add(-9.0 + 16.0 * i / 399.0, 0.0, 0);
  for (int i = 0; i < 12; ++i) add(8.0, 0.5 + 3.0 * i / 11.0, 2);
  for (int i = 0; i < 400; ++i) add(7.0 - 16.0 * i / 399.0, 4.0, 1);
  s.f.num_groups = groups ? 3 : 0;
  return s;
}

// Squared residuals of the frame term (loss "none", per point) summed per wall: the term's own weighting
// (the frame weight times each point's Assignment::sw) at pose x.
std::map<int, double> cost_per_wall(const LocalizationMap& map, const Scene& s, const std::vector<Assignment>& as,
                                    const Pose2& x, double weight) {
  const double pose[3] = {x.x, x.y, x.yaw};
  auto term = make_frame_term(pose, *map.lookup, s.f, as, "none", 0.0, weight, /*compact=*/false);
  std::vector<double> r(as.size());
  const double* params[1] = {pose};
  EXPECT_TRUE(term->Evaluate(params, r.data(), nullptr));
  std::map<int, double> out;
  for (size_t i = 0; i < as.size(); ++i) out[s.wall_of[size_t(as[i].point)]] += r[i] * r[i];
  return out;
}

}  // namespace

TEST(ElementQuota, AFewPointsWallKeepsThemAllAndTheCostEstimatesTheWholeFrame) {
  for (const bool groups : {false, true}) {
    SCOPED_TRACE(groups ? "PCA groups" : "no groups");
    const Scene s = scene(groups);
    const auto map = make_localization_map(s.plan, "brute-force");
    ASSERT_TRUE(map.lookup->element_targets());
    const Pose2 x{0.03, -0.02, 0.004};  // a few cm and a quarter degree off the truth (identity)
    const int stride = 7;
    AssignOptions ao;
    ao.gate_m = 0.3;
    ao.stride = stride;
    std::vector<Assignment> plain, budget, all;
    assign(*map.lookup, s.f, x, ao, &plain);
    ao.element_quota = 30;
    assign(*map.lookup, s.f, x, ao, &budget);
    // The same from the points selected once (what the matcher and the optimizer do per frame).
    std::vector<SampledPoint> sel;
    select_points(*map.lookup, s.f, x, ao, &sel);
    AssignOptions given = ao;
    given.stride = 1;
    given.element_quota = 0;
    given.points = &sel;
    std::vector<Assignment> from_sel;
    assign(*map.lookup, s.f, x, given, &from_sel);
    EXPECT_TRUE(from_sel == budget);
    ao.stride = 1;
    assign(*map.lookup, s.f, x, ao, &all);
    ASSERT_EQ(all.size(), s.f.points.size());

    // Every stride-th point: the short wall keeps 1-2 of its 12 (what the test is about).
    int short_plain = 0;
    for (const auto& a : plain) short_plain += s.wall_of[size_t(a.point)] == 2;
    EXPECT_LE(short_plain, 2);

    // With the quota: all 12 of the short wall at sampling weight 1/sqrt(stride), the long walls every
    // stride-th point at weight 1.
    int short_kept = 0, long_kept = 0;
    for (const auto& a : budget) {
      if (s.wall_of[size_t(a.point)] == 2) {
        ++short_kept;
        EXPECT_FLOAT_EQ(a.sw, float(1 / std::sqrt(double(stride))));
      } else {
        ++long_kept;
        EXPECT_EQ(a.point % stride, 0) << a.point;
        EXPECT_EQ(a.sw, 1.0f);
      }
    }
    EXPECT_EQ(short_kept, 12);
    EXPECT_EQ(long_kept, int(plain.size()) - short_plain);

    // The term weighted by sqrt(stride) (the optimizer's budget weight) estimates the cost over all points:
    // exactly on the short wall (all its points, each counted once), within a few percent on the long walls
    // (every stride-th point of a smooth residual), and so on the whole frame.
    const auto c_all = cost_per_wall(map, s, all, x, 1.0);
    const auto c_est = cost_per_wall(map, s, budget, x, std::sqrt(double(stride)));
    ASSERT_GT(c_all.at(2), 0);
    EXPECT_NEAR(c_est.at(2), c_all.at(2), 1e-6 * c_all.at(2));  // the weight is a float
    for (int w : {0, 1}) EXPECT_NEAR(c_est.at(w), c_all.at(w), 0.05 * c_all.at(w)) << "wall " << w;
    double sum_all = 0, sum_est = 0;
    for (int w : {0, 1, 2}) sum_all += c_all.at(w), sum_est += c_est.at(w);
    EXPECT_NEAR(sum_est, sum_all, 0.03 * sum_all);

    // The Gauss-Newton information of the short wall (the position along the corridor, x) is likewise that of
    // all its points, scaled as the rest of the frame (1 / stride): not 0-2 points' worth.
    std::vector<Assignment> short_only;
    for (const auto& a : budget)
      if (s.wall_of[size_t(a.point)] == 2) short_only.push_back(a);
    std::vector<Assignment> short_all;
    for (const auto& a : all)
      if (s.wall_of[size_t(a.point)] == 2) short_all.push_back(a);
    const Eigen::Matrix3d h_est = frame_information(*map.lookup, s.f, short_only, x, "none", 0.0);
    const Eigen::Matrix3d h_all = frame_information(*map.lookup, s.f, short_all, x, "none", 0.0);
    EXPECT_NEAR(h_est(0, 0) * stride, h_all(0, 0), 1e-6 * h_all(0, 0));
  }
}

TEST(ElementQuota, NothingChangesWithoutAStride) {
  const Scene s = scene(true);
  const auto map = make_localization_map(s.plan, "brute-force");
  AssignOptions ao;
  ao.gate_m = 0.3;
  std::vector<Assignment> a, b;
  assign(*map.lookup, s.f, Pose2{0.02, 0.01, 0.0}, ao, &a);
  ao.element_quota = 30;
  assign(*map.lookup, s.f, Pose2{0.02, 0.01, 0.0}, ao, &b);
  EXPECT_TRUE(a == b);
}

TEST(ElementQuota, AnElementAboveTheQuotaIsStrided) {
  // The quota counts the points whose closest element (within the gate) it is: at 11 the short wall's 12 are
  // strided as the long walls' are.
  const Scene s = scene(false);
  const auto map = make_localization_map(s.plan, "brute-force");
  AssignOptions ao;
  ao.gate_m = 0.3;
  ao.stride = 7;
  ao.element_quota = 11;
  std::vector<Assignment> as;
  assign(*map.lookup, s.f, Pose2{0.0, 0.0, 0.0}, ao, &as);
  for (const auto& a : as) {
    EXPECT_EQ(a.point % 7, 0);
    EXPECT_EQ(a.sw, 1.0f);
  }
  ao.element_quota = 12;
  assign(*map.lookup, s.f, Pose2{0.0, 0.0, 0.0}, ao, &as);
  int short_kept = 0;
  for (const auto& a : as) short_kept += s.wall_of[size_t(a.point)] == 2;
  EXPECT_EQ(short_kept, 12);
}
