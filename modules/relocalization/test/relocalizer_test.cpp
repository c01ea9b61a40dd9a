#include "fploc/relocalization/relocalizer.h"
#include "fploc/relocalization/schedule.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "fploc/matcher/lookup.h"
#include "fploc/matcher/map.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::reloc;
namespace synth = fploc::testing;

namespace {

double yaw_err(double a, double b) { return std::abs(std::remainder(a - b, 2 * M_PI)); }

synth::SynthOptions noisy(uint32_t seed) {
  synth::SynthOptions o;
  o.noise_sigma = 0.02;
  o.clutter_fraction = 0.2;
  o.seed = seed;
  return o;
}

}  // namespace

// No initial pose at all. The room is almost symmetric under a half turn about its centre (doors at
// x 4-5 south and 15-16 north): only the notch and the pillars (few points) tell the two poses apart,
// so near the walls a single scan may be reported ambiguous — then with the truth as the best
// candidate. It must never be confidently wrong, and most poses are found outright.
TEST(Relocalizer, FindsThePoseInTheRoomWithoutAGuess) {
  auto map = matcher::make_localization_map(synth::room_with_pillars(), "annf-exact");
  Relocalizer reloc(*map.plan, *map.lookup);
  EXPECT_GT(reloc.free_cells(), 300u);
  const Pose2 poses[] = {{3, 3, 0.3}, {10, 7, 2.0}, {16, 2, -1.2}, {18, 8, 3.0}, {5, 8, -2.5}, {10, 2.5, 1.0}};
  uint32_t seed = 1;
  int found = 0;
  for (const auto& truth : poses) {
    const FeatureFrame f = synth::synth_frame(*map.plan, truth, noisy(seed++));
    const RelocResult r = reloc.locate(f);
    SCOPED_TRACE(r.text);
    std::cerr << "  (" << truth.x << ", " << truth.y << ", " << truth.yaw << "): " << r.text << "\n";
    ASSERT_NE(r.status, RelocStatus::kNoFit) << "at (" << truth.x << ", " << truth.y << ", " << truth.yaw << ")";
    found += r.status == RelocStatus::kFound;
    // Found, or ambiguous with the truth as the best candidate.
    EXPECT_LT(std::hypot(r.pose.x - truth.x, r.pose.y - truth.y), 0.05);
    EXPECT_LT(yaw_err(r.pose.yaw, truth.yaw), 1.0 * M_PI / 180);
    EXPECT_GT(r.fit.inlier_ratio, 0.6);
  }
  EXPECT_GE(found, 4) << "of 6 poses";
}

// A 4-fold symmetric corridor ring: one scan cannot tell the four places apart. The answer must be
// "ambiguous" (with the truth among the candidates), never a confident wrong pose.
TEST(Relocalizer, SymmetricCorridorIsAmbiguousNotWrong) {
  auto map = matcher::make_localization_map(synth::corridor_loop(), "annf-exact");
  Relocalizer reloc(*map.plan, *map.lookup);
  const Pose2 poses[] = {{1, 12, 1.5}, {12, 1, 0.1}, {23, 18, -1.6}};
  uint32_t seed = 7;
  for (const auto& truth : poses) {
    const RelocResult r = reloc.locate(synth::synth_frame(*map.plan, truth, noisy(seed++)));
    SCOPED_TRACE(r.text);
    std::cerr << "  (" << truth.x << ", " << truth.y << ", " << truth.yaw << "): " << r.text << "\n";
    if (r.status == RelocStatus::kFound) {
      EXPECT_LT(std::hypot(r.pose.x - truth.x, r.pose.y - truth.y), 0.1) << "confidently wrong";
    } else {
      EXPECT_EQ(r.status, RelocStatus::kAmbiguous);
    }
    bool truth_listed = false;
    for (const auto& c : r.candidates)
      truth_listed |= std::hypot(c.pose.x - truth.x, c.pose.y - truth.y) < 0.2 && yaw_err(c.pose.yaw, truth.yaw) < 0.05;
    EXPECT_TRUE(truth_listed) << "the true pose is not among the " << r.candidates.size() << " candidates";
  }
}

// Features that belong to no place on the plan: no pose is accepted.
TEST(Relocalizer, RandomFeaturesFitNowhere) {
  auto map = matcher::make_localization_map(synth::room_with_pillars(), "annf-exact");
  Relocalizer reloc(*map.plan, *map.lookup);
  const RelocResult r = reloc.locate(synth::random_frame(400, 8.0, 3));
  EXPECT_NE(r.status, RelocStatus::kFound) << r.text;
  EXPECT_FALSE(r.text.empty());
  EXPECT_EQ(reloc.locate(FeatureFrame{}).status, RelocStatus::kNoFit);
}

// Recovery after a loss: a search in a disc around the last pose, 2.5 m / 60 deg off the truth.
TEST(Relocalizer, RegionSearchAroundALostPose) {
  auto map = matcher::make_localization_map(synth::room_with_pillars(), "annf-exact");
  Relocalizer reloc(*map.plan, *map.lookup);
  const Pose2 truth{12, 8, -0.7};
  SearchRegion region{{10.5, 6.0, truth.yaw + 1.0}, 3.0, M_PI};
  const RelocResult r = reloc.locate(synth::synth_frame(*map.plan, truth, noisy(11)), region);
  ASSERT_EQ(r.status, RelocStatus::kFound) << r.text;
  EXPECT_LT(std::hypot(r.pose.x - truth.x, r.pose.y - truth.y), 0.05);
  // A smaller search than the whole plan.
  const RelocResult all = reloc.locate(synth::synth_frame(*map.plan, truth, noisy(11)));
  EXPECT_LT(r.hypotheses, all.hypotheses / 3);
}

// A local search answers within its region: a seed whose refinement slides out of the disc (here onto the truth,
// 1.2 m from a disc of 0.6 m: the robot cannot have driven there since its last good pose) is another place. The
// same scan searched in a disc around the truth is found.
TEST(Relocalizer, ALocalSearchAnswersWithinItsRegion) {
  auto map = matcher::make_localization_map(synth::room_with_pillars(), "annf-exact");
  Relocalizer reloc(*map.plan, *map.lookup);
  const Pose2 truth{12, 8, -0.7};
  const FeatureFrame f = synth::synth_frame(*map.plan, truth, noisy(11));
  const RelocResult near = reloc.locate(f, SearchRegion{{truth.x + 1.2, truth.y, truth.yaw}, 0.6, M_PI});
  std::cerr << "  disc 1.2 m away: " << to_string(near.status) << " " << near.text << "\n";
  for (const auto& c : near.candidates)
    EXPECT_LE(std::hypot(c.pose.x - truth.x - 1.2, c.pose.y - truth.y), 0.6 + RelocalizerConfig{}.grid_m) << "outside the region";
  if (near.status == RelocStatus::kFound) EXPECT_GT(std::hypot(near.pose.x - truth.x, near.pose.y - truth.y), 0.5);
  const RelocResult at = reloc.locate(f, SearchRegion{{truth.x + 0.2, truth.y, truth.yaw}, 0.6, M_PI});
  ASSERT_EQ(at.status, RelocStatus::kFound) << at.text;
  EXPECT_LT(std::hypot(at.pose.x - truth.x, at.pose.y - truth.y), 0.05);
}

// The fploc-relocalizer's local radius: what the platform can drive since the last good pose, at most region_radius_m.
TEST(Schedule, LocalRadiusIsWhatThePlatformCanHaveDriven) {
  Schedule s;
  EXPECT_DOUBLE_EQ(local_radius_m(s, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(local_radius_m(s, 0.5), 1.5);
  EXPECT_DOUBLE_EQ(local_radius_m(s, 5.0), 3.0);
  s.max_speed_mps = 0;
  EXPECT_DOUBLE_EQ(local_radius_m(s, 0.5), 3.0);
}

TEST(Relocalizer, RejectsBadConfiguration) {
  auto map = matcher::make_localization_map(synth::room_with_pillars(), "annf-exact");
  RelocalizerConfig c;
  c.grid_m = 0;
  EXPECT_THROW(Relocalizer(*map.plan, *map.lookup, c), std::runtime_error);
  EXPECT_THROW(Relocalizer(FloorPlan{}, *map.lookup), std::runtime_error);
}
