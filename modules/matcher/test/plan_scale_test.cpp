// Online drawing-scale correction (plan_scale.h): a building 0.5 % larger than its drawing biases the
// registration by s times the distance from the plan's centre; against the plan scaled by the estimate
// about that centre the bias is gone. And when ScaleCorrection applies an estimate.
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/matcher/plan_scale.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::matcher;

TEST(PlanScale, ScaledPlanRemovesTheScaleBias) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  const Eigen::Vector2d c = scale_centre(plan);
  const Box2 b = plan.bounds();
  EXPECT_NEAR(c.x(), 0.5 * (b.min.x() + b.max.x()), 1e-12);
  const double s = 0.005;
  const FloorPlan world = scaled_plan(plan, 1 + s, c);
  ASSERT_EQ(world.elements.size(), plan.elements.size());
  // Element kinds and ids kept, geometry scaled about c.
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    EXPECT_EQ(world.elements[i].kind, plan.elements[i].kind);
    EXPECT_NEAR((world.elements[i].a - c).norm(), (1 + s) * (plan.elements[i].a - c).norm(), 1e-9);
    EXPECT_NEAR(world.elements[i].r, (1 + s) * plan.elements[i].r, 1e-12);
  }
  auto raw = make_localization_map(plan, "annf-exact");
  auto corrected = make_localization_map(scaled_plan(plan, 1 + s, c), "annf-exact");
  MatcherConfig cfg;
  cfg.max_iterations = 30;
  cfg.max_rounds = 8;
  fploc::testing::SynthOptions so;
  so.max_range = 30;
  double worst_raw = 0, worst_corr = 0;
  for (const Pose2 truth : {Pose2{3.0, 5.0, 0.2}, Pose2{16.0, 2.5, -1.0}, Pose2{10.0, 8.0, 2.0}}) {
    const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
    const MatchResult r0 = register_frame(*raw.lookup, f, truth, cfg);
    const MatchResult r1 = register_frame(*corrected.lookup, f, truth, cfg);
    ASSERT_EQ(r0.status, FitStatus::kOk);
    ASSERT_EQ(r1.status, FitStatus::kOk);
    worst_raw = std::max(worst_raw, std::hypot(r0.pose.x - truth.x, r0.pose.y - truth.y));
    worst_corr = std::max(worst_corr, std::hypot(r1.pose.x - truth.x, r1.pose.y - truth.y));
    // The raw fit lies roughly where the pose is in the drawing, centre + (p - centre) / (1 + s) (not exactly:
    // the scan's own distances are the building's, a compromise between the walls in view).
    const Pose2 in_plan = rescaled_pose(truth, 1 + s, 1.0, c);
    EXPECT_LT(std::hypot(r0.pose.x - in_plan.x, r0.pose.y - in_plan.y), 0.03);
  }
  EXPECT_GT(worst_raw, 0.015) << "0.5 % of 5-8 m from the centre: the raw fit should be centimetres off";
  EXPECT_LT(worst_corr, 0.002);
}

TEST(PlanScale, RescaledPoseRoundTrips) {
  const Eigen::Vector2d c(10, 5);
  const Pose2 p{14, 1, 0.3};
  const Pose2 q = rescaled_pose(p, 1.0, 1.01, c);
  EXPECT_NEAR(q.x, 10 + 1.01 * 4, 1e-12);
  EXPECT_NEAR(q.y, 5 - 1.01 * 4, 1e-12);
  EXPECT_EQ(q.yaw, p.yaw);
  const Pose2 back = rescaled_pose(q, 1.01, 1.0, c);
  EXPECT_NEAR(back.x, p.x, 1e-12);
  EXPECT_NEAR(back.y, p.y, 1e-12);
}

TEST(PlanScale, CorrectionOnlyWhenSignificant) {
  ScaleCorrection sc;
  EXPECT_FALSE(sc.update(0.0005, 0.0001));  // 0.05 %: below min_error (a clean plan's estimate)
  EXPECT_FALSE(sc.update(0.003, 0.001));    // 3 sigma: not yet
  EXPECT_FALSE(sc.update(0.004, 0.0));      // no sigma: nothing to tell
  EXPECT_FALSE(sc.update(std::nan(""), 0.001));
  auto a = sc.update(0.0045, 0.0002);       // significant: applied
  ASSERT_TRUE(a);
  EXPECT_DOUBLE_EQ(*a, 0.0045);
  EXPECT_FALSE(sc.update(0.0047, 0.0001));  // moved 0.02 %: kept
  auto b = sc.update(0.0052, 0.0001);       // moved 0.07 %: re-applied
  ASSERT_TRUE(b);
  EXPECT_DOUBLE_EQ(sc.applied(), 0.0052);
  EXPECT_FALSE(sc.update(0.0049, 0.0015));  // lost some significance (3.3 sigma) but keeps half: kept
  auto c = sc.update(0.0003, 0.0002);       // no longer significant: the correction is taken back
  ASSERT_TRUE(c);
  EXPECT_EQ(*c, 0.0);
  EXPECT_EQ(sc.applied(), 0.0);
}

TEST(PlanScale, PlanCorrectionGivesAMapOnlyWhenTheCorrectionChanges) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  std::string said;
  PlanCorrection off(false, false);
  EXPECT_FALSE(off.enabled());
  EXPECT_EQ(off.update(plan, 0.0045, 0.0002, {}, 0, "annf-exact", &said), nullptr);  // off: never
  PlanCorrection pc(true, false);
  EXPECT_TRUE(pc.enabled());
  EXPECT_EQ(pc.update(plan, 0.003, 0.001, {}, 0, "annf-exact", &said), nullptr);  // not significant yet
  auto map = pc.update(plan, 0.0045, 0.0002, {}, 1, "annf-exact", &said);
  ASSERT_NE(map, nullptr);
  EXPECT_DOUBLE_EQ(pc.scale(), 0.0045);
  EXPECT_EQ(said, "plan corrected: scale +0.450 % (estimate +0.450 +- 0.020 %)");
  EXPECT_NEAR(map->plan->bounds().max.x() - map->plan->bounds().min.x(),
              1.0045 * (plan.bounds().max.x() - plan.bounds().min.x()), 1e-9);
  EXPECT_EQ(pc.update(plan, 0.0047, 0.0001, {}, 2, "annf-exact", &said), nullptr);  // kept: no new map
}
