// ActivePlan: the plan a node's Localizer works on (floor, diff weights, plan correction).
#include <gtest/gtest.h>

#include "fploc/localizer/active_plan.h"
#include "synthetic.h"

namespace fploc::localizer {
namespace {

ActivePlan room(bool scale) {
  return ActivePlan(one_floor(matcher::make_localization_map(testing::room_with_pillars()), "room"), 0.0f,
                    matcher::PlanCorrection(scale, false), "annf-exact");
}

TEST(ActivePlan, FlagsOutsideThePlanAreRefusedAndNamed) {
  ActivePlan p = room(false);
  std::string error;
  const int n = int(p.plan().elements.size());
  EXPECT_TRUE(p.apply_flags({{0, matcher::DiffVerdict::kMissing}}, &error));
  EXPECT_TRUE(error.empty());
  EXPECT_FALSE(p.apply_flags({{n, matcher::DiffVerdict::kMissing}}, &error));
  EXPECT_NE(error.find("element " + std::to_string(n) + " not in the plan"), std::string::npos) << error;
}

TEST(ActivePlan, AFlaggedElementIsLeftOutOfTheLocalizersConfig) {
  ActivePlan p = room(false);
  std::string error;
  ASSERT_TRUE(p.apply_flags({{2, matcher::DiffVerdict::kMissing}}, &error));
  auto loc = p.make_localizer(Config{});
  ASSERT_NE(loc, nullptr);
  // The weights the Localizer reads are the plan's: element 2 at weight 0 (plan_diff_weight 0).
  const auto* w = loc->config().matcher.element_weight;
  ASSERT_NE(w, nullptr);
  EXPECT_EQ((*w)[2], 0.0f);
  EXPECT_EQ((*w)[0], 1.0f);
  p.set_floor(0);  // a (new) floor starts unflagged
  auto again = p.make_localizer(Config{});
  EXPECT_EQ((*again->config().matcher.element_weight)[2], 1.0f);
}

TEST(ActivePlan, NoCorrectionWhenOffAndANewMapWhenTheScaleIsSignificant) {
  std::string said, error;
  ActivePlan off = room(false);
  EXPECT_FALSE(off.correct(0.02, 0.001, {}, 1'000'000, &said, &error));
  ActivePlan on = room(true);
  bool changed = false;
  for (int i = 0; i < 30 && !changed; ++i)
    changed = on.correct(0.02, 0.001, {}, int64_t(i + 1) * 1'000'000, &said, &error);
  EXPECT_TRUE(changed);
  EXPECT_TRUE(error.empty());
  EXPECT_FALSE(said.empty());
  EXPECT_GT(on.scale(), 0.0);
}

}  // namespace
}  // namespace fploc::localizer
