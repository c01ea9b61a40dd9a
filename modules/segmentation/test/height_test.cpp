// The height/attitude estimator on synthetic multi-height scans: a room whose ceiling is lower over one
// half (a drop ceiling, as a corridor next to a hall), a ceiling with beams and lamps, and a walk from
// one area into the other. z must follow the truth within 1-2 cm without a jump, with its source named.
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/segmentation/attitude_height.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"
#include "seg_test_util.h"

using namespace fploc;
using namespace fploc::seg;
using fploc::seg::synth::SensorPose;

namespace {
constexpr double kDeg = M_PI / 180.0;

using test_util::HeightTally;
using test_util::two_height_room;

HeightTally walk(const synth::Room& room, double x0, double x1, int n, uint32_t seed) {
  SegmenterConfig cfg;  // floor-to-ceiling height learned online
  RingSegmenter seg(cfg);
  const auto beams = synth::os1_like_beams();
  HeightTally w;
  for (int k = 0; k < n; ++k) {
    const double f = double(k) / (n - 1);
    SensorPose pose{x0 + (x1 - x0) * f, 0.5 * std::sin(3 * f), 1.4 + 0.04 * std::sin(7 * f),
                    0.6 * kDeg * std::sin(11 * f), 0.5 * kDeg * std::cos(13 * f), 0.2 * k};
    const auto& out = seg.process(synth::render(room, pose, beams, 1024, 0.01, 0.01, seed + k).scan);
    w.add(out, pose, true, k > 0);
  }
  return w;
}
}  // namespace

// From the high part of the room under the drop ceiling and back: the paper's single learned room height
// would put z 0.6 m off under the drop ceiling; the estimator takes z from the floor while the ceiling does
// not fit the learned height, and re-learns the height when the new ceiling persists.
TEST(HeightEstimator, WalkUnderADropCeiling) {
  const auto room = two_height_room(3.0);
  const HeightTally w = walk(room, 6.5, -6.5, 60, 100);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);  // never a jump
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);  // the p99 target, here for every scan
  EXPECT_GT(w.ground, 0);   // the floor carried z across the edge
  EXPECT_GT(w.ceiling, 0);  // and the ceiling again once the new height was learned
}

TEST(HeightEstimator, BeamsAndLampsOnTheCeiling) {
  synth::Room room;
  room.height = 3.0;
  for (double x = -7.0; x <= 7.0; x += 2.0) {  // beams 0.3 m deep, 0.25 m wide across the room
    synth::Box b;
    b.lo = Eigen::Vector3d(x, -6.0, 2.7);
    b.hi = Eigen::Vector3d(x + 0.25, 6.0, 3.0);
    b.label = synth::kClutter;
    room.boxes.push_back(b);
  }
  for (double x = -6.0; x <= 6.0; x += 3.0)  // lamps hanging 0.5 m
    for (double y = -4.0; y <= 4.0; y += 4.0) {
      synth::Box l;
      l.lo = Eigen::Vector3d(x, y, 2.4);
      l.hi = Eigen::Vector3d(x + 0.6, y + 0.6, 2.5);
      l.label = synth::kClutter;
      room.boxes.push_back(l);
    }
  const HeightTally w = walk(room, -5.0, 5.0, 40, 300);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);
  EXPECT_LT(w.max_rp_err, 0.1 * kDeg);
}

// A tilted "ceiling" (a sloped patch under a roof) over the sensor with the flat floor seen: the planes
// disagree, the floor gives attitude and height.
TEST(HeightEstimator, SlopedCeilingGivesWayToTheFloor) {
  synth::Room room;
  room.height = 3.0;
  // A staircase of 0.1 m steps rising 0.15 m per metre across the room approximates a sloped ceiling.
  for (int i = 0; i < 16; ++i) {
    synth::Box s;
    s.lo = Eigen::Vector3d(-8.0 + i, -6.0, 2.2 + 0.15 * i);
    s.hi = Eigen::Vector3d(-7.0 + i, 6.0, 6.0);
    s.label = synth::kCeiling;
    room.boxes.push_back(s);
  }
  room.wall_top = 6.0;
  const HeightTally w = walk(room, -4.0, 4.0, 30, 500);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);
}

namespace {
// One scan's planes as the fits give them (sensor frame): the ceiling `cd` above the sensor, its normal tilted
// `ceiling_tilt_deg` about y (a sloped roof), the level floor `gd` below.
Segmentation planes(double cd, double gd, double ceiling_tilt_deg) {
  Segmentation s;
  const double t = ceiling_tilt_deg * kDeg;
  s.ceiling.coeffs << -std::sin(t), 0.0, -std::cos(t), cd;  // normal into the room: down
  s.ground.coeffs << 0.0, 0.0, 1.0, gd;
  for (Plane* p : {&s.ceiling, &s.ground}) {
    p->found = true;
    p->inliers = 2000;
    p->rms_m = 0.01;
    p->tilt_sigma = 0.01 * kDeg;
    p->d_sigma = 0.001;
  }
  return s;
}
}  // namespace

// A sloped roof seen with the level floor (building-areas' roof corner): the planes disagree, attitude and z
// come from the floor, and the roof's distances are no floor-to-ceiling height. Learned into the running
// median they shifted it by 2.5 cm, under the 3 cm consistency gate, and the level ceiling met next put z off
// by that much until the median forgot them (room plan, building-areas-medium: 2.3 cm for 1.4 s at 56 s).
TEST(HeightEstimator, SlopedCeilingIsNotLearnedAsTheRoomHeight) {
  SegmenterConfig cfg;  // floor-to-ceiling height learned online
  AttitudeHeight ah(cfg);
  const ImuPrior no_imu;
  for (int k = 0; k < 25; ++k) {  // level ceiling 3.0 m above the floor, the sensor 1.2 m up
    Segmentation s = planes(1.8, 1.2, 0.0);
    ah.update(s, no_imu);
    ASSERT_EQ(s.z_source, HeightSource::kCeiling);
  }
  EXPECT_NEAR(ah.room_height(), 3.0, 1e-9);
  for (int k = 0; k < 30; ++k) {  // under the roof: tilted 6 deg, 3.025 m along its normal
    Segmentation s = planes(1.825, 1.2, 6.0);
    ah.update(s, no_imu);
    EXPECT_EQ(s.attitude_source, AttitudeSource::kGround);
    EXPECT_EQ(s.z_source, HeightSource::kGround);
    EXPECT_NEAR(s.z, 1.2, 1e-9);
  }
  EXPECT_NEAR(ah.room_height(), 3.0, 1e-9);
  double worst = 0;
  for (int k = 0; k < 10; ++k) {  // the level ceiling again
    Segmentation s = planes(1.8, 1.2, 0.0);
    ah.update(s, no_imu);
    EXPECT_EQ(s.z_source, HeightSource::kCeiling);
    worst = std::max(worst, std::abs(s.z - 1.2));
  }
  EXPECT_LT(worst, 0.002);
}

// A far ceiling patch (a high hall seen only beyond ~9 m by the upper rings): its fit's tilt a little off
// moves its distance at the sensor by cm while the fit claims mm. Ceiling + ground then differ from the
// area's learned height by more than 3 of their sigmas, though well inside the 3 cm "another area" gate:
// z comes from the floor's distance, not from the ceiling's (room plan, building-areas-medium, 93-96 s:
// 1-2 cm for 2 s).
TEST(HeightEstimator, CeilingOffByMoreThanItsSigmaGivesWayToTheFloor) {
  SegmenterConfig cfg;
  AttitudeHeight ah(cfg);
  const ImuPrior no_imu;
  for (int k = 0; k < 30; ++k) {
    Segmentation s = planes(1.8, 1.2, 0.0);
    ah.update(s, no_imu);
  }
  double worst = 0;
  int from_ground = 0;
  for (int k = 0; k < 10; ++k) {  // the ceiling's distance 1.5 cm short (alternating with exact scans)
    Segmentation s = planes(k % 2 ? 1.8 : 1.785, 1.2, k % 2 ? 0.0 : 0.2);
    ah.update(s, no_imu);
    worst = std::max(worst, std::abs(s.z - 1.2));
    from_ground += s.z_source == HeightSource::kGround;
  }
  EXPECT_LT(worst, 0.002);
  EXPECT_EQ(from_ground, 5);
  EXPECT_NEAR(ah.room_height(), 3.0, 1e-9);  // the area's height is unchanged (same area)
}
