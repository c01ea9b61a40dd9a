#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "pipeline.h"

namespace {
std::string shared_dir() { return std::filesystem::exists(FPLOC_SHARED_DIR) ? FPLOC_SHARED_DIR : ""; }
}  // namespace

// The first 12 s of a simulated room sequence through the whole library chain: the matcher stays
// registered and both stages are within a decimetre of the ground truth (the full-sequence numbers
// against the targets are in docs/notes/localization.md, from localization_e2e).
TEST(EndToEnd, RoomSequenceStaysRegistered) {
  fploc::e2e::Options o;
  o.scenario = "room-small-loop-fast";
  o.max_frames = 120;
  o.shared_dir = shared_dir();
  const auto r = fploc::e2e::run(fploc::FloorPlan{}, o);
  std::printf("frames %d ok %d ATE sfr %.4f wo %.4f odo %.4f m; us/scan seg %.0f feat %.0f match %.0f opt %.0f\n", r.frames,
              r.ok_frames, r.ate_sfr, r.ate_wo, r.ate_odo, r.us_segment, r.us_features, r.us_matcher, r.us_optimizer);
  ASSERT_EQ(r.frames, 120);
  EXPECT_GE(r.ok_frames, 108);
  EXPECT_EQ(r.lost_frames, 0);
  EXPECT_EQ(r.wo.size(), r.sfr.size());
  EXPECT_LT(r.ate_sfr, 0.10);
  EXPECT_LT(r.ate_wo, 0.10);
}

TEST(EndToEnd, WrongInitialPoseConverges) {
  fploc::e2e::Options o;
  o.scenario = "room-small-loop-fast";
  o.max_frames = 30;
  o.shared_dir = shared_dir();
  o.init_dx = 0.7;
  o.init_dy = -0.7;
  o.init_dyaw = 10 * M_PI / 180;
  const auto r = fploc::e2e::run(fploc::FloorPlan{}, o);
  ASSERT_FALSE(r.sfr.empty());
  // After convergence the last poses are on the ground truth.
  const auto& e = r.sfr.back();
  const auto& g = r.gt.back();
  EXPECT_LT((e.p - g.p).head<2>().norm(), 0.10);
}
