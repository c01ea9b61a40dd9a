#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/matcher/plan_terms.h"
#include "synthetic.h"

using namespace fploc;
using fploc::testing::room_with_pillars;
using fploc::testing::synth_frame;
using fploc::testing::SynthOptions;

namespace {

double pos_err(const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double yaw_err(const Pose2& a, const Pose2& b) { return std::abs(wrap_angle(a.yaw - b.yaw)); }

std::vector<std::string> available_lookups() {
  std::vector<std::string> out;
  for (const auto& n : lookup_names())
    if (have_annf() || n.rfind("annf", 0) != 0) out.push_back(n);
  return out;
}

const std::vector<Pose2> kPoses = {{3.0, 2.5, 0.3}, {10.0, 5.0, -1.2}, {16.5, 7.5, 2.8}, {5.0, 8.0, 1.6}, {17.0, 2.0, -2.5}};

class LookupTest : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(LookupTest, ExactRecoveryWithoutNoise) {
  auto map = make_localization_map(room_with_pillars(), GetParam());
  MatcherConfig cfg;
  cfg.max_iterations = 30;
  cfg.max_outer = 8;
  // Point-to-point against 5 cm samples cannot be exact: its floor is the sampling error. The paper's
  // ANNF (two candidates per leaf, depth 7 = 9.4 cm leaves) gives a wrong element near some element
  // ends, which costs millimetres: measured 0.1-1.8 mm here.
  const bool paper = GetParam().find("paper") != std::string::npos;
  const double tol = GetParam() == "kdtree" ? 0.02 : paper ? 0.005 : 1e-4;
  for (const auto& truth : kPoses) {
    SynthOptions so;
    const FeatureFrame f = synth_frame(*map.plan, truth, so);
    const Pose2 guess{truth.x + 0.2, truth.y - 0.15, truth.yaw + 0.05};
    const MatchResult r = register_frame(*map.lookup, f, guess, cfg);
    EXPECT_EQ(r.status, FitStatus::kOk) << GetParam() << " " << r.text;
    EXPECT_LT(pos_err(r.pose, truth), tol) << GetParam() << " at " << truth.x << "," << truth.y;
    EXPECT_LT(yaw_err(r.pose, truth), tol) << GetParam();
    EXPECT_GT(r.fit.inlier_ratio, paper ? 0.9 : 0.95);
  }
}

TEST_P(LookupTest, ConvergesFromOneMetreTenDegreesWithNoiseAndClutter) {
  auto map = make_localization_map(room_with_pillars(), GetParam());
  MatcherConfig cfg;
  cfg.max_outer = 8;
  int converged = 0, total = 0;
  const double offsets[4][3] = {{1.0, 0, 10}, {0, -1.0, -10}, {-0.7, 0.7, 10}, {0.7, 0.7, -10}};
  // Point-to-point registration (kdtree) does not have this basin of convergence (about a third of
  // these cases stall 5-75 cm off: the paper's Section III argument; see the notes and the bench).
  // It is held to a correct registration from the motion model's typical error (20 cm / 2 deg).
  const double scale = GetParam() == "kdtree" ? 0.2 : 1.0;
  for (size_t i = 0; i < kPoses.size(); ++i) {
    for (const auto& o : offsets) {
      SynthOptions so;
      so.noise_sigma = 0.02;
      so.clutter_fraction = 0.2;
      so.seed = uint32_t(7 + i);
      const Pose2& truth = kPoses[i];
      const FeatureFrame f = synth_frame(*map.plan, truth, so);
      const Pose2 guess{truth.x + scale * o[0], truth.y + scale * o[1], truth.yaw + scale * o[2] * M_PI / 180};
      const MatchResult r = register_frame(*map.lookup, f, guess, cfg);
      ++total;
      if (r.status == FitStatus::kOk && pos_err(r.pose, truth) < 0.05 && yaw_err(r.pose, truth) < 0.01) ++converged;
    }
  }
  EXPECT_EQ(converged, total) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(AllLookups, LookupTest, ::testing::ValuesIn(available_lookups()),
                         [](const auto& info) {
                           std::string s = info.param;
                           for (auto& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

TEST(Lookup, CandidatesContainTheNearestElement) {
  const FloorPlan plan = room_with_pillars();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-1, 21), uy(-1, 11);
  for (const auto& name : available_lookups()) {
    if (name == "kdtree" || name.find("paper") != std::string::npos) continue;  // approximate by design
    auto map = make_localization_map(plan, name);
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector2d p(ux(rng), uy(rng));
      double d_true = 0;
      nearest_element_brute_force(plan, p, &d_true);
      int cand[kMaxCandidates];
      const int n = map.lookup->candidates(p, cand, kMaxCandidates);
      ASSERT_GT(n, 0);
      Eigen::Vector2d q;
      EXPECT_NEAR(closest_of(map.lookup->targets(), cand, n, p, &q, nullptr), d_true, 1e-9) << name;
    }
  }
}

TEST(Lookup, UnknownNameIsAnError) {
  EXPECT_THROW(make_localization_map(room_with_pillars(), "nearest-ish"), std::runtime_error);
}

TEST(Matcher, FeaturesThatDoNotMatchArePoorThenLost) {
  auto map = make_localization_map(room_with_pillars(), "brute-force");
  MatcherConfig cfg;
  cfg.lost_after = 3;
  Matcher m(*map.lookup, cfg);
  const Pose2 start{10, 5, 0.4};
  m.set_pose(start);
  // First a good frame, then garbage: the pose must stay at the prediction (no jump), POOR then LOST.
  SynthOptions so;
  auto good = synth_frame(*map.plan, start, so, 1'000'000);
  EXPECT_EQ(m.process(good).status, FitStatus::kOk);
  for (int k = 1; k <= 5; ++k) {
    auto bad = fploc::testing::random_frame(300, 6.0, uint32_t(100 + k));
    bad.utime = 1'000'000 + k * 100'000;
    const MatchResult r = m.process(bad);
    EXPECT_NE(r.status, FitStatus::kOk);
    EXPECT_EQ(r.status, k < 3 ? FitStatus::kPoor : FitStatus::kLost) << k;
    EXPECT_LT(pos_err(r.pose, start), 1e-6) << "the pose jumped on a poor fit";
    EXPECT_LT(r.fit.inlier_ratio, cfg.min_inlier_ratio);
  }
  // Matching features again: recovers.
  auto again = synth_frame(*map.plan, Pose2{10.1, 5.05, 0.42}, so, 2'000'000);
  const MatchResult r = m.process(again);
  EXPECT_EQ(r.status, FitStatus::kOk) << r.text;
  EXPECT_LT(pos_err(r.pose, Pose2{10.1, 5.05, 0.42}), 1e-3);
}

TEST(Matcher, NotInitialisedWithoutAPose) {
  auto map = make_localization_map(room_with_pillars(), "brute-force");
  Matcher m(*map.lookup, {});
  EXPECT_EQ(m.process(synth_frame(*map.plan, {5, 5, 0}, {})).status, FitStatus::kNotInitialised);
}

TEST(Matcher, TracksAMovingSensorWithTheMotionModel) {
  auto map = make_localization_map(room_with_pillars(), "brute-force");
  MatcherConfig cfg;
  Matcher m(*map.lookup, cfg);
  m.set_pose({2.5, 2.0, 0.0});
  double max_err = 0;
  for (int k = 0; k < 60; ++k) {
    const double t = k * 0.1;
    // 0.9 m/s with a turn.
    const Pose2 truth{2.5 + 0.9 * t, 2.0 + 0.3 * t + 0.05 * t * t, 0.2 * t};
    SynthOptions so;
    so.noise_sigma = 0.02;
    so.clutter_fraction = 0.1;
    so.seed = uint32_t(k + 1);
    const MatchResult r = m.process(synth_frame(*map.plan, truth, so, int64_t(t * 1e6)));
    ASSERT_EQ(r.status, FitStatus::kOk) << k << " " << r.text;
    max_err = std::max(max_err, pos_err(r.pose, truth));
    if (k > 2) {
      // The constant-velocity prediction is close to the truth (within one frame's acceleration).
      EXPECT_LT(pos_err(r.predicted, truth), 0.05) << k;
    }
  }
  EXPECT_LT(max_err, 0.03);
}

TEST(Matcher, ImuYawDeltaDrivesThePredictedYaw) {
  auto map = make_localization_map(room_with_pillars(), "brute-force");
  Matcher m(*map.lookup, {});
  m.set_pose({10, 5, 0.0});
  SynthOptions so;
  EXPECT_EQ(m.process(synth_frame(*map.plan, {10, 5, 0.0}, so, 0)).status, FitStatus::kOk);
  const MatchResult r = m.process(synth_frame(*map.plan, {10, 5, 0.3}, so, 100'000), 0.3);
  EXPECT_NEAR(r.predicted.yaw, 0.3, 1e-12);
  EXPECT_LT(yaw_err(r.pose, {10, 5, 0.3}), 1e-4);
}

TEST(PlanTerms, GroupPointsShareOneElement) {
  auto map = make_localization_map(room_with_pillars(), "brute-force");
  // Sensor near the south-west corner looking at the south wall; the guess is shifted so that the
  // ends of the south-wall group are nearer the west wall.
  const Pose2 truth{1.0, 1.0, 0.0};
  SynthOptions so;
  so.beams = 720;
  const FeatureFrame f = synth_frame(*map.plan, truth, so);
  const Pose2 guess{0.6, 1.2, 0.0};
  AssignOptions ao;
  ao.gate_m = 2.0;
  std::vector<Assignment> with, without;
  assign(*map.lookup, f, guess, ao, &with);
  ao.group_rule = false;
  assign(*map.lookup, f, guess, ao, &without);
  std::map<int, std::set<int>> elements_of_group, elements_free;
  for (const auto& a : with)
    if (f.points[size_t(a.point)].group >= 0) elements_of_group[f.points[size_t(a.point)].group].insert(a.cand[0]);
  for (const auto& a : without)
    if (f.points[size_t(a.point)].group >= 0) elements_free[f.points[size_t(a.point)].group].insert(a.cand[0]);
  ASSERT_FALSE(elements_of_group.empty());
  bool some_group_split_without_rule = false;
  for (const auto& [g, els] : elements_of_group) EXPECT_EQ(els.size(), 1u) << "group " << g;
  for (const auto& [g, els] : elements_free) some_group_split_without_rule |= els.size() > 1;
  EXPECT_TRUE(some_group_split_without_rule) << "the test case does not exercise the rule";
  // And the registration from that guess lands on the truth with the rule.
  MatcherConfig cfg;
  const MatchResult r = register_frame(*map.lookup, f, guess, cfg);
  EXPECT_LT(pos_err(r.pose, truth), 1e-4);
}

TEST(PlanTerms, CovarianceIsLargeAlongACorridor) {
  // A straight corridor: translation along it is unobservable from two parallel walls.
  FloorPlan plan;
  plan.elements.push_back(Element::segment({-50, 0}, {50, 0}));
  plan.elements.push_back(Element::segment({-50, 2}, {50, 2}));
  auto map = make_localization_map(plan, "brute-force");
  SynthOptions so;
  so.max_range = 10;
  const FeatureFrame f = synth_frame(plan, {0, 1, 0}, so);
  const MatchResult r = register_frame(*map.lookup, f, {0.0, 1.1, 0.02}, MatcherConfig{});
  EXPECT_NEAR(r.pose.y, 1.0, 1e-4);
  EXPECT_GT(r.covariance(0, 0), 100 * r.covariance(1, 1));
}
