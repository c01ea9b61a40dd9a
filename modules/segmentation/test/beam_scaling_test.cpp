// Sensor-dependent segmenter numbers from the beam pattern (issue 13 item 2): the reference sensor keeps
// the options' values; sparser/denser sensors get scaled ones; the segmenter finds the planes of a
// synthetic room with 16, 32, 64 and 128 beams.
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/segmentation/beam_scaling.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"
#include "seg_test_util.h"

using namespace fploc;
using namespace fploc::seg;

namespace {
BeamIntrinsics uniform(int n, double top, double bottom) {
  BeamIntrinsics b;
  for (int u = 0; u < n; ++u) {
    b.altitude_deg.push_back(top - u * (top - bottom) / (n - 1));
    b.azimuth_deg.push_back(0.0);
  }
  return b;
}
}  // namespace

TEST(BeamScaling, ReferenceSensorKeepsTheOptions) {
  const SegmenterConfig cfg;
  const BeamScaling s = beam_scaling(synth::os1_like_beams(64), 1024, cfg);
  EXPECT_DOUBLE_EQ(s.pixel_scale, 1.0);
  EXPECT_EQ(s.seed_rings, cfg.seed_rings);
  EXPECT_EQ(s.start_stride, 24u);
  EXPECT_EQ(s.final_stride, 3u);
  EXPECT_EQ(s.min_plane_inliers, cfg.min_plane_inliers);
  EXPECT_EQ(s.min_inlier_fraction, cfg.min_inlier_fraction);
}

TEST(BeamScaling, SparseAndDenseSensors) {
  const SegmenterConfig cfg;
  const BeamScaling v16 = beam_scaling(uniform(16, 15, -15), 1024, cfg);  // VLP-16-like
  EXPECT_EQ(v16.seed_rings, 2);  // 2 deg apart: one ring in the reference band, at least two
  EXPECT_EQ(v16.start_stride, 6u);
  EXPECT_EQ(v16.final_stride, 1u);
  EXPECT_EQ(v16.min_plane_inliers, 50);
  const BeamScaling o128 = beam_scaling(uniform(128, 22.5, -22.5), 1024, cfg);  // 0.35 deg apart
  EXPECT_EQ(o128.seed_rings, 6);
  EXPECT_EQ(o128.start_stride, 48u);
  EXPECT_EQ(o128.final_stride, 6u);
  EXPECT_EQ(o128.min_plane_inliers, 400);
  const BeamScaling half = beam_scaling(synth::os1_like_beams(64), 512, cfg);  // 512 columns
  EXPECT_EQ(half.start_stride, 12u);
  EXPECT_EQ(half.min_plane_inliers, 100);
  EXPECT_EQ(v16.min_inlier_fraction, cfg.min_inlier_fraction);   // 15, 13, 11, 9 of 8 upper rings >= 8.3 deg
  EXPECT_EQ(o128.min_inlier_fraction, cfg.min_inlier_fraction);  // never stricter than the option
  // OS-1-32 "gradient" (a real unit's altitudes): 2 of its 16 upper rings above 8.3 deg.
  BeamIntrinsics g;
  g.altitude_deg = {12.75, 10.03, 7.27, 4.47, 3.41, 2.35, 2.02, 1.65, 1.29, 0.93, 0.6, 0.23, -0.13, -0.49, -0.83, -1.17,
                    -1.54, -1.88, -2.24, -2.6, -2.96, -3.65, -4.36, -5.06, -5.76, -7.17, -8.57, -9.95, -11.31, -12.66, -14.01, -15.32};
  g.azimuth_deg.assign(32, 0.0);
  const BeamScaling s32 = beam_scaling(g, 1024, cfg);
  EXPECT_DOUBLE_EQ(s32.min_inlier_fraction, cfg.min_inlier_fraction * 0.25);
  EXPECT_EQ(s32.seed_rings, 2);
}

TEST(BeamScaling, SegmenterFindsTheRoomWithEveryBeamCount) {
  const synth::Room room = synth::furnished_room();
  synth::SensorPose pose;
  pose.roll = 2 * M_PI / 180;
  pose.pitch = -1.5 * M_PI / 180;
  for (int n : {16, 32, 64, 128}) {
    SCOPED_TRACE(n);
    const BeamIntrinsics beams = n == 16 ? uniform(16, 15, -15) : uniform(n, n == 128 ? 22.5 : 16.6, n == 128 ? -22.5 : -16.6);
    const synth::SynthScan sc = synth::render(room, pose, beams, 1024, 0.01, 0.01, 7);
    RingSegmenter sg{SegmenterConfig{}};
    sg.set_keep_labels(true);
    const Segmentation& out = sg.process(sc.scan);
    ASSERT_TRUE(out.ceiling.found) << out.status_text;
    ASSERT_TRUE(out.ground.found) << out.status_text;
    EXPECT_NEAR(out.roll, pose.roll, 0.1 * M_PI / 180);
    EXPECT_NEAR(out.pitch, pose.pitch, 0.1 * M_PI / 180);
    EXPECT_NEAR(out.ground.distance(), pose.z, 0.01);
    const auto ws = test_util::wall_stats(out, sc.label);
    EXPECT_GT(ws.precision, 0.99);
    EXPECT_GT(ws.recall, 0.9);
    EXPECT_EQ(sg.beam_scaling().min_plane_inliers, int(std::lround(200.0 * n / 64)));
  }
}
