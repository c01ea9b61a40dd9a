// Per-element weights of the floor-plan terms (element_weights.h): a wall that stands 15 cm from where the
// plan draws it biases the registration; with the plan diff's verdict (weight 0) it does not.
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/matcher/element_weights.h"
#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/matcher/plan_terms.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::matcher;

namespace {
// The synthetic room with its west wall (element 5, x = 0) standing 0.15 m further in.
FloorPlan moved_west_wall() {
  FloorPlan w = fploc::testing::room_with_pillars();
  w.elements[5] = Element::segment({0.15, 10}, {0.15, 0});
  return w;
}
}  // namespace

TEST(ElementWeights, MovedWallLeftOutRemovesItsBias) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  auto map = make_localization_map(plan, "annf-exact");
  const Pose2 truth{3.0, 5.0, 0.2};
  fploc::testing::SynthOptions so;
  so.max_range = 6.0;  // the east wall (x = 20) out of range: x is held by the west wall and the pillar
  const FeatureFrame f = fploc::testing::synth_frame(moved_west_wall(), truth, so);
  MatcherConfig cfg;
  cfg.max_iterations = 30;
  cfg.max_rounds = 8;
  const MatchResult biased = register_frame(*map.lookup, f, truth, cfg);
  ASSERT_EQ(biased.status, FitStatus::kOk);
  const double e0 = std::hypot(biased.pose.x - truth.x, biased.pose.y - truth.y);
  EXPECT_GT(e0, 0.01) << "a wall 15 cm off should pull the pose (else the test shows nothing)";

  const std::vector<float> w = element_weights(plan, {{5, DiffVerdict::kMoved}});
  ASSERT_EQ(w.size(), plan.elements.size());
  EXPECT_EQ(w[5], 0.0f);
  EXPECT_EQ(w[0], 1.0f);
  cfg.element_weight = &w;
  const MatchResult r = register_frame(*map.lookup, f, truth, cfg);
  ASSERT_EQ(r.status, FitStatus::kOk);
  const double e1 = std::hypot(r.pose.x - truth.x, r.pose.y - truth.y);
  EXPECT_LT(e1, 0.003);
  EXPECT_LT(e1, 0.2 * e0);

  // No assignment has the left-out element as a candidate.
  AssignOptions ao;
  ao.gate_m = 0.3;
  ao.element_weight = &w;
  std::vector<Assignment> as;
  assign(*map.lookup, f, truth, ao, &as);
  ASSERT_FALSE(as.empty());
  for (const auto& a : as)
    for (int k = 0; k < a.n; ++k) EXPECT_NE(a.cand[k], 5);
}

TEST(ElementWeights, TwinFaceOfATwoLineWallFollows) {
  FloorPlan p;
  p.elements.push_back(Element::segment({0, 0}, {5, 0}));       // 0: a wall's south face
  p.elements.push_back(Element::segment({5, 0.12}, {0, 0.12})); // 1: its north face (12 cm wall)
  p.elements.push_back(Element::segment({0, 3}, {5, 3}));       // 2: another wall, 3 m away
  p.elements.push_back(Element::segment({6, 0}, {6, 3}));       // 3: perpendicular
  const std::vector<int> t = wall_twins(p);
  EXPECT_EQ(t[0], 1);
  EXPECT_EQ(t[1], 0);
  EXPECT_EQ(t[2], -1);
  EXPECT_EQ(t[3], -1);
  ElementWeights ew(p, DiffWeightOptions{0.0f, 0.25f});
  EXPECT_FALSE(ew.update({}));
  EXPECT_TRUE(ew.update({{0, DiffVerdict::kMoved}, {99, DiffVerdict::kMissing}}));  // 99: not in the plan, ignored
  EXPECT_EQ((*ew.weights())[0], 0.25f);
  EXPECT_EQ((*ew.weights())[1], 0.25f);
  EXPECT_EQ((*ew.weights())[2], 1.0f);
  EXPECT_EQ(ew.flagged(), 2);
  EXPECT_FALSE(ew.update({{0, DiffVerdict::kMoved}}));
  EXPECT_TRUE(ew.update({{2, DiffVerdict::kMissing}}));
  EXPECT_EQ((*ew.weights())[0], 1.0f);
  EXPECT_EQ((*ew.weights())[2], 0.0f);
}
