// The height/attitude estimator with a building floor's area ceilings and the plan pose, and on ramps and
// thresholds, on synthetic scans: a room whose ceiling is lower over one part (heights from the building,
// or learned per area online), a ramp under a flat ceiling (the robot pitches with the ramp, z rises with
// it), and a door threshold (a brief jolt). z must follow the truth within 1-2 cm without a jump, roll/pitch
// within 0.2 deg, with the source named.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"
#include "seg_test_util.h"

using namespace fploc;
using namespace fploc::seg;
using fploc::seg::synth::SensorPose;

namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr double kG = 9.80665;

using test_util::two_height_room;

AreaCeiling rect_area(const std::string& name, double x0, double y0, double x1, double y1, double h) {
  AreaCeiling a;
  a.name = name;
  a.polygon = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  a.height_m = h;
  a.origin = {x0, y0};
  return a;
}

struct Walk : test_util::HeightTally {
  int n = 0;
  std::string last_status;
  bool said_building = false, said_learned = false;
};

enum class Imu { kNone, kSteady, kShakenOnJolt };

struct Options {
  const AreaCeilingMap* areas = nullptr;
  Imu imu = Imu::kNone;
  int jolt_scan = -1;  // this scan's pose is jolted (a threshold under the wheels)
  bool building_attitude = true;  // SegmenterConfig::building_attitude
};

// Drives through `room` along `xs` (x per scan), y wiggling; the sensor 1.4 m above the floor under it and
// pitched with the floor's slope there. The plan pose fed back is the previous scan's truth (the localizer's
// latency).
Walk walk(const synth::Room& room, const std::vector<double>& xs, uint32_t seed, const Options& opt) {
  SegmenterConfig cfg;
  cfg.use_imu_prior = opt.imu != Imu::kNone;
  cfg.building_attitude = opt.building_attitude;
  RingSegmenter seg(cfg);
  if (opt.areas) seg.set_areas(*opt.areas);
  const auto beams = synth::os1_like_beams();
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Walk w;
  const int n = int(xs.size());
  for (int k = 0; k < n; ++k) {
    const double f = double(k) / std::max(1, n - 1);
    const double x = xs[size_t(k)];
    const double slope = (room.floor_at(x + 0.05) - room.floor_at(x - 0.05)) / 0.1;
    SensorPose pose{x, 0.5 * std::sin(3 * f), room.floor_at(x) + 1.4 + 0.02 * std::sin(7 * f),
                    0.4 * kDeg * std::sin(11 * f), -std::atan(slope) + 0.3 * kDeg * std::cos(13 * f), 0.1 * k};
    if (k == opt.jolt_scan) {
      pose.pitch += 1.5 * kDeg;
      pose.roll -= 0.8 * kDeg;
      pose.z += 0.012;
    }
    const int64_t utime = 1000000 + int64_t(k) * 100000;
    if (opt.imu != Imu::kNone) {
      const Eigen::Vector3d up = up_from_roll_pitch(pose.roll, pose.pitch);
      const bool shaken = opt.imu == Imu::kShakenOnJolt && k == opt.jolt_scan;
      for (int i = 0; i < 10; ++i) {
        Eigen::Vector3d a = kG * up + 0.05 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
        if (shaken) a += Eigen::Vector3d(0.0, 0.0, (i % 2 ? 4.0 : -4.0)) + Eigen::Vector3d(3.0 * gauss(rng), 0, 0);
        seg.add_accel(a);
      }
    }
    auto scan = synth::render(room, pose, beams, 1024, 0.01, 0.01, seed + k).scan;
    scan.utime = utime;
    const auto& out = seg.process(scan);
    // The localizer's pose of this scan arrives before the next one.
    seg.set_plan_pose({utime, pose.x, pose.y, pose.yaw, true});
    w.add(out, pose, k >= 2, k > 2);  // the first scans learn
    w.said_building = w.said_building || out.status_text.find("building height") != std::string::npos;
    w.said_learned = w.said_learned || out.status_text.find("learned height") != std::string::npos;
    w.last_status = out.status_text;
    if (std::getenv("FPLOC_TEST_VERBOSE"))
      std::printf("k %d x %.2f z %.4f true %.4f src %s rp %.3f/%.3f true %.3f/%.3f att %s | %s\n", k, x, out.z, pose.z,
                  to_string(out.z_source), out.roll / kDeg, out.pitch / kDeg, pose.roll / kDeg, pose.pitch / kDeg,
                  to_string(out.attitude_source), out.status_text.c_str());
    ++w.n;
  }
  return w;
}

std::vector<double> line(double x0, double x1, int n) {
  std::vector<double> xs;
  for (int k = 0; k < n; ++k) xs.push_back(x0 + (x1 - x0) * k / (n - 1));
  return xs;
}
}  // namespace

// The building gives both heights: the ceiling carries z across the edge (each ceiling point with the height
// of the area it lies in), never the floor, never a jump.
TEST(AreaHeights, BuildingHeightsAcrossAnEdge) {
  const auto room = two_height_room(3.0);
  AreaCeilingMap map;
  map.default_height_m = 3.2;
  map.areas.push_back(rect_area("drop ceiling", -8.0, -6.0, 3.0, 6.0, 2.6));
  Options o;
  o.areas = &map;
  const Walk w = walk(room, line(6.5, -6.5, 60), 100, o);
  EXPECT_LT(w.max_z_err, 0.01);
  EXPECT_LT(w.max_step, 0.01);
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);
  EXPECT_EQ(w.ceiling, w.n) << w.last_status;  // the ceiling all the way
  EXPECT_TRUE(w.said_building);
}

// The building has the areas but no heights: each is learned online (from scans whose ceiling lies in it);
// on the way back both are known and the ceiling gives z on both sides of the edge.
TEST(AreaHeights, LearnedPerAreaOnline) {
  const auto room = two_height_room(3.0);
  AreaCeilingMap map;  // heights unknown (0)
  map.areas.push_back(rect_area("drop ceiling", -8.0, -6.0, 3.0, 6.0, 0.0));
  Options o;
  o.areas = &map;
  std::vector<double> xs = line(6.5, -6.5, 50);
  const std::vector<double> back = line(-6.5, 6.5, 50);
  xs.insert(xs.end(), back.begin(), back.end());
  const Walk w = walk(room, xs, 200, o);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);
  EXPECT_TRUE(w.said_learned);
  EXPECT_GT(w.ceiling, 80) << w.last_status;
}

// A ramp under a flat ceiling: the robot pitches with the ramp (2.9 deg) and rises 0.3 m. The floor then
// looks level to the sensor and the ceiling tilted, as under a sloped ceiling; the IMU's gravity (steady
// here) says which, and z follows the ramp from the ceiling (its height learned on the level part of a
// long hall before the ramp).
TEST(AreaHeights, RampWithTheImu) {
  synth::Room room;
  room.half_x = 20;
  room.height = 3.2;
  room.ramp = {2.0, 8.0, 0.3};
  Options o;
  o.imu = Imu::kSteady;
  const Walk w = walk(room, line(-16.0, 14.0, 90), 300, o);
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);
}

// The same ramp without an IMU, in a building whose ceiling is flat there: the building decides.
TEST(AreaHeights, RampWithAFlatBuildingCeiling) {
  synth::Room room;
  room.height = 3.2;
  room.ramp = {-2.0, 4.0, 0.3};
  AreaCeilingMap map;
  map.default_height_m = 3.2;
  Options o;
  o.areas = &map;
  const Walk w = walk(room, line(-6.0, 7.0, 60), 400, o);
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);
  EXPECT_TRUE(w.said_building);
}

// A ramp whose ceiling follows it (3.2 m above its surface, as in a ramp corridor): ceiling and floor
// agree and both are tilted 2.9 deg with the robot; only the building's sloped ceiling area says so.
TEST(AreaHeights, RampUnderAParallelCeiling) {
  synth::Room room;
  room.half_x = 20;
  room.height = 3.2;
  room.wall_top = 3.6;
  room.ramp = {-2.0, 4.0, 0.3, true};
  AreaCeilingMap map;
  map.default_height_m = 3.2;
  AreaCeiling ramp = rect_area("ramp", -2.0, -6.0, 4.0, 6.0, 3.2);
  ramp.slope = {0.05, 0.0};
  map.areas.push_back(ramp);
  map.areas.push_back(rect_area("landing", 4.0, -6.0, 20.0, 6.0, 3.5));
  Options o;
  o.areas = &map;
  const Walk w = walk(room, line(-12.0, 10.0, 70), 600, o);
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);
  EXPECT_LT(w.max_z_err, 0.02);
  EXPECT_LT(w.max_step, 0.02);
}

// A door threshold: one scan jolted (1.5 deg pitch, 0.8 deg roll, 1.2 cm up) with the IMU shaken in it.
// Both planes move with the robot: roll/pitch and z follow it.
TEST(AreaHeights, ThresholdJolt) {
  const auto room = synth::furnished_room();
  Options o;
  o.imu = Imu::kShakenOnJolt;
  o.jolt_scan = 12;
  const Walk w = walk(room, line(-4.0, 4.0, 25), 500, o);
  EXPECT_LT(w.max_rp_err, 0.2 * kDeg);
  EXPECT_LT(w.max_z_err, 0.02);
}

// A far patch of another area's ceiling is the plane fitted (room : building-areas-medium at 92.6-95.2 s: under the
// 2.65 m drop ceiling, the 3.8 m high hall 9-11 m away seen by the upper rings): its distance a little off (its tilt
// over a lever of 10 m), inside the 3 cm consistency gate. With the building's exact height z was off by as much
// (2.9 cm there); the level floor disagrees by more than 3 sigmas and 1 cm: z from the floor.
TEST(AreaHeights, FarCeilingOffByMoreThanItsSigmaGivesWayToTheFloor) {
  SegmenterConfig cfg;
  AttitudeHeight ah(cfg);
  AreaCeilingMap map;
  map.default_height_m = 2.65;
  map.areas.push_back(rect_area("high hall", -12.0, -3.0, -8.0, 3.0, 3.8));
  ah.set_areas(map);
  const ImuPrior no_imu;
  double worst = 0;
  int from_ground = 0, from_ceiling = 0;
  for (int k = 0; k < 20; ++k) {
    const double cd = k % 2 ? 2.6 : 2.62;  // every other scan the hall's plane 2 cm high
    Candidates upper;
    for (double x = -11.0; x <= -9.0; x += 0.1)
      for (double y = -2.0; y <= 2.0; y += 0.1) upper.push(Eigen::Vector3f(float(x), float(y), float(cd)), 10.0f, 0);
    upper.fill_points();
    Segmentation s;
    s.utime = 1000000 + int64_t(k) * 100000;
    s.ceiling.coeffs << 0.0, 0.0, -1.0, cd;
    s.ground.coeffs << 0.0, 0.0, 1.0, 1.2;
    for (Plane* p : {&s.ceiling, &s.ground}) {
      p->found = true;
      p->inliers = int(upper.size());
      p->rms_m = 0.01;
      p->tilt_sigma = 0.01 * kDeg;
      p->d_sigma = 0.001;
    }
    ah.set_plan_pose({s.utime - 50000, 0.0, 0.0, 0.0, true});
    ah.update(s, no_imu, &upper);
    if (k < 2) continue;
    worst = std::max(worst, std::abs(s.z - 1.2));
    from_ground += s.z_source == HeightSource::kGround;
    from_ceiling += s.z_source == HeightSource::kCeiling;
    if (std::getenv("FPLOC_TEST_VERBOSE")) std::printf("k %d z %.4f | %s\n", k, s.z, s.status_text.c_str());
  }
  EXPECT_LT(worst, 0.002);
  EXPECT_EQ(from_ground, 9);   // the scans 2 cm off
  EXPECT_EQ(from_ceiling, 9);  // the exact ones: the building's height
}
