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

// A pose d metres from the plan's scale centre, with a unit covariance in the fit's own terms.
Pose pose_at(const ActivePlan& p, const Eigen::Vector2d& d) {
  Pose q;
  const Eigen::Vector2d at = matcher::scale_centre(p.plan()) + d;
  q.pose = {at.x(), at.y(), 0.3};
  q.covariance = Eigen::Matrix3d::Identity() * 1e-6;
  return q;
}

TEST(ActivePlan, ADrawingScaleErrorWidensThePublishedCovarianceAlongTheRadius) {
  std::string said, error;
  ActivePlan p = room(false);  // the correction off: the whole estimated scale error stays in the poses
  Pose before = pose_at(p, {3, 4});
  p.add_scale_error(&before);
  EXPECT_EQ(before.covariance, Eigen::Matrix3d::Identity() * 1e-6) << "no estimate yet: nothing added";

  p.correct(0.005, 0.0005, {}, 1'000'000, &said, &error);  // 0.5 % +- 0.05 %
  const double s2 = 0.005 * 0.005 - 0.0005 * 0.0005;
  EXPECT_NEAR(p.unexplained_scale_squared(), s2, 1e-12);
  Pose q = pose_at(p, {3, 4});  // 5 m out along (0.6, 0.8): 0.5 % of it is 2.5 cm
  p.add_scale_error(&q);
  const Eigen::Vector2d radial(0.6, 0.8), across(-0.8, 0.6);
  EXPECT_NEAR(radial.dot(q.covariance.topLeftCorner<2, 2>() * radial), 1e-6 + s2 * 25, 1e-9);
  EXPECT_NEAR(across.dot(q.covariance.topLeftCorner<2, 2>() * across), 1e-6, 1e-9);
  EXPECT_EQ(q.covariance(2, 2), 1e-6) << "a scale moves no heading";
  Pose centre = pose_at(p, {0, 0});
  p.add_scale_error(&centre);
  EXPECT_EQ(centre.covariance, Eigen::Matrix3d::Identity() * 1e-6) << "the scale centre does not move";

  // An estimate within its sigma (a plan drawn to scale) adds nothing; a bad estimate leaves the last one.
  p.correct(0.0004, 0.0005, {}, 2'000'000, &said, &error);
  EXPECT_EQ(p.unexplained_scale_squared(), 0.0);
  p.correct(std::nan(""), 0.0005, {}, 3'000'000, &said, &error);
  EXPECT_EQ(p.unexplained_scale_squared(), 0.0);
}

TEST(ActivePlan, TheCorrectedScaleIsNoLongerInThePublishedCovariance) {
  std::string said, error;
  ActivePlan on = room(true);
  for (int i = 0; i < 30 && on.scale() == 0; ++i) on.correct(0.02, 0.001, {}, int64_t(i + 1) * 1'000'000, &said, &error);
  ASSERT_GT(on.scale(), 0.0);
  EXPECT_EQ(on.unexplained_scale_squared(), 0.0) << "estimate 2 % +- 0.1 %, 2 % applied";
  on.correct(0.0203, 0.0001, {}, 40'000'000, &said, &error);  // 0.03 % more than applied (below min_change)
  EXPECT_NEAR(on.unexplained_scale_squared(), (0.0203 - on.scale()) * (0.0203 - on.scale()) - 1e-8, 1e-12);
  EXPECT_GT(on.unexplained_scale_squared(), 0.0);
}

}  // namespace
}  // namespace fploc::localizer
