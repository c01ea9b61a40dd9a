#include <gtest/gtest.h>

#include <cmath>

#include "fploc/segmentation/ransac_segmenter.h"
#include "fploc/segmentation/synthetic.h"
#include "seg_test_util.h"

using namespace fploc;
using namespace fploc::seg;

namespace {
constexpr double kDeg = M_PI / 180.0;
}

TEST(RansacSegmenter, TiltedFurnishedRoom) {
  const auto room = synth::furnished_room();
  synth::SensorPose pose{-1.0, 0.5, 1.45, 2.0 * kDeg, -3.0 * kDeg, 0.4};
  auto s = synth::render(room, pose, synth::os1_like_beams(), 1024, 0.01, 0.02, 7);
  RansacSegmenter seg(SegmenterConfig{});
  seg.set_keep_labels(true);
  const auto& out = seg.process(s.scan);
  ASSERT_EQ(out.status, SegStatus::kOk) << out.status_text;
  EXPECT_STREQ(seg.name(), "ransac");
  // RANSAC + PCL's least-squares refinement on the inliers: looser than the M-estimator.
  EXPECT_NEAR(out.roll, pose.roll, 0.3 * kDeg);
  EXPECT_NEAR(out.pitch, pose.pitch, 0.3 * kDeg);
  EXPECT_NEAR(out.z, pose.z, 0.05);
  const auto st = test_util::wall_stats(out, s.label);
  EXPECT_GE(st.precision, 0.98);
  EXPECT_GE(st.recall, 0.85);
}

TEST(RansacSegmenter, BadInputAndNoCeiling) {
  RansacSegmenter seg(SegmenterConfig{});
  EXPECT_EQ(seg.process(Scan{}).status, SegStatus::kEmpty);
  synth::Room room;
  room.ceiling = false;
  room.wall_top = 40;
  const auto& out = seg.process(synth::render(room, synth::SensorPose{}, synth::os1_like_beams(), 512, 0, 0, 1).scan);
  EXPECT_EQ(out.status, SegStatus::kNoCeiling);
  EXPECT_EQ(out.attitude_source, AttitudeSource::kGround);  // the floor is seen (no ceiling, no history)
  EXPECT_NEAR(out.roll, 0.0, 0.1 * M_PI / 180);
}
