#include "fploc/localizer/localizer.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "fploc/floorplan/free_space.h"
#include "fploc/localizer/floor_maps.h"
#include "fploc/matcher/map.h"
#include "fploc/matcher/plan_terms.h"
#include "synthetic.h"

using namespace fploc;
using fploc::testing::room_with_pillars;
using fploc::testing::synth_frame;
using fploc::testing::SynthOptions;

namespace {

// A smooth path through the room at ~0.6 m/s, 10 Hz, turning at up to ~0.16 rad/s.
Pose2 truth_at(double t) { return {3.0 + 0.6 * t, 3.0 + 1.5 * std::sin(0.25 * t), 0.2 * std::sin(0.3 * t) + 0.1 * t}; }
double yaw_rate_at(double t) { return 0.06 * std::cos(0.3 * t) + 0.1; }

std::vector<FeatureFrame> make_frames(const FloorPlan& plan, int n) {
  std::vector<FeatureFrame> frames;
  for (int k = 0; k < n; ++k) {
    const double t = 0.1 * k;
    SynthOptions so;
    so.seed = uint32_t(k + 1);
    so.noise_sigma = 0.01;
    so.sweep_s = 0.1;
    so.sweep_twist = matcher::log_twist(truth_at(t), truth_at(t + so.sweep_s), so.sweep_s);
    frames.push_back(synth_frame(plan, truth_at(t), so, int64_t(std::llround(t * 1e6))));
    frames.back().scan_seq = k;
    frames.back().z = 1.2;
    frames.back().z_sigma = 0.01;
    frames.back().roll_pitch_sigma = 0.001;
  }
  return frames;
}

void feed_imu(localizer::Localizer& loc, double t0, double t1) {
  for (double t = t0; t < t1; t += 0.01) loc.add_imu(int64_t(std::llround(t * 1e6)), yaw_rate_at(t));
}

class LocalizerTest : public ::testing::Test {
 protected:
  LocalizerTest() : map_(matcher::make_localization_map(room_with_pillars(), "annf-exact")), frames_(make_frames(*map_.plan, 60)) {}
  matcher::LocalizationMap map_;
  std::vector<FeatureFrame> frames_;
};

TEST_F(LocalizerTest, NotInitialisedUntilSetPose) {
  localizer::Localizer loc(*map_.lookup, {});
  std::vector<localizer::Pose> finals;
  const auto s = loc.process(frames_[0], &finals);
  EXPECT_EQ(s.sfr.match.status, matcher::FitStatus::kNotInitialised);
  EXPECT_FALSE(s.latest);
  EXPECT_TRUE(finals.empty());
}

// Both steps in one process: every frame is registered, the window's final poses are every frame's,
// in time order, on the truth, and carry the frames' own sigmas.
TEST_F(LocalizerTest, TracksASequenceAndItsPosesCarryTheirSigmas) {
  localizer::Localizer loc(*map_.lookup, {});
  loc.set_pose(truth_at(0));
  std::vector<localizer::Pose> finals;
  double sfr_err2 = 0;
  for (size_t k = 0; k < frames_.size(); ++k) {
    feed_imu(loc, 0.1 * k - 0.1, 0.1 * k + 0.11);
    const auto s = loc.process(frames_[k], &finals);
    ASSERT_EQ(s.sfr.match.status, matcher::FitStatus::kOk) << "frame " << k;
    ASSERT_TRUE(s.latest);
    EXPECT_EQ(s.latest->utime, frames_[k].utime);
    const Pose2 g = truth_at(0.1 * k);
    sfr_err2 += std::pow(s.sfr.match.pose.x - g.x, 2) + std::pow(s.sfr.match.pose.y - g.y, 2);
  }
  loc.flush(&finals);
  ASSERT_EQ(finals.size(), frames_.size());
  double wo_err2 = 0;
  for (size_t k = 0; k < finals.size(); ++k) {
    EXPECT_EQ(finals[k].utime, frames_[k].utime);
    EXPECT_TRUE(finals[k].final_estimate);
    EXPECT_DOUBLE_EQ(finals[k].z_sigma, 0.01);
    EXPECT_DOUBLE_EQ(finals[k].roll_pitch_sigma, 0.001);
    const Pose2 g = truth_at(0.1 * k);
    wo_err2 += std::pow(finals[k].pose.x - g.x, 2) + std::pow(finals[k].pose.y - g.y, 2);
  }
  EXPECT_LT(std::sqrt(sfr_err2 / frames_.size()), 0.03);
  EXPECT_LT(std::sqrt(wo_err2 / frames_.size()), 0.03);
}

// The SFR step holds the last known roll/pitch/z when the frame's own are unknown, and says so by the
// frame's own (unknown) sigmas.
TEST_F(LocalizerTest, AttitudeHold) {
  localizer::Localizer loc(*map_.lookup, {});
  loc.set_pose(truth_at(0));
  FeatureFrame f0 = frames_[0];
  f0.roll = 0.01;
  f0.pitch = -0.02;
  const auto s0 = loc.register_frame(f0);
  EXPECT_DOUBLE_EQ(s0.z, 1.2);
  FeatureFrame f1 = frames_[1];
  f1.z = 7;
  f1.z_sigma = kUnknownZSigmaM;
  f1.roll = f1.pitch = 0.3;
  f1.roll_pitch_sigma = kUnknownRollPitchSigmaRad;
  const auto s1 = loc.register_frame(f1);
  EXPECT_DOUBLE_EQ(s1.z, 1.2);
  EXPECT_DOUBLE_EQ(s1.roll, 0.01);
  EXPECT_DOUBLE_EQ(s1.pitch, -0.02);
  EXPECT_EQ(s1.z_sigma, kUnknownZSigmaM);
  EXPECT_EQ(s1.roll_pitch_sigma, kUnknownRollPitchSigmaRad);
  // Known again: used as they come.
  FeatureFrame f2 = frames_[2];
  f2.z = 1.3;
  const auto s2 = loc.register_frame(f2);
  EXPECT_DOUBLE_EQ(s2.z, 1.3);
}

// The two steps called separately (as the matcher and optimizer processes do) give what process()
// gives without the feedback.
TEST_F(LocalizerTest, TwoStepsEqualOneProcessWithoutFeedback) {
  localizer::Config cfg;
  cfg.refine_from_window = false;
  localizer::Localizer a(*map_.lookup, cfg), sfr(*map_.lookup, cfg), wo(*map_.lookup, cfg);
  a.set_pose(truth_at(0));
  sfr.set_pose(truth_at(0));
  std::vector<localizer::Pose> fa, fb;
  for (size_t k = 0; k < 30; ++k) {
    feed_imu(a, 0.1 * k - 0.1, 0.1 * k + 0.11);
    feed_imu(sfr, 0.1 * k - 0.1, 0.1 * k + 0.11);
    const auto s = a.process(frames_[k], &fa);
    const auto r = sfr.register_frame(frames_[k]);
    const auto latest = wo.optimize(frames_[k], r, &fb);
    EXPECT_EQ(s.sfr.match.pose.x, r.match.pose.x);
    EXPECT_EQ(s.sfr.match.pose.yaw, r.match.pose.yaw);
    ASSERT_TRUE(latest && s.latest);
    EXPECT_EQ(latest->pose.x, s.latest->pose.x);
  }
  ASSERT_EQ(fa.size(), fb.size());
  for (size_t i = 0; i < fa.size(); ++i) EXPECT_EQ(fa[i].pose.y, fb[i].pose.y);
}

}  // namespace

// Odometry at its own rate (20 Hz, not at the scans' times): a frame's odometry pose is interpolated between the
// samples around it, so frames a second apart (too far for the constant-velocity model) are predicted by the
// odometry's increment to millimetres; without odometry the prediction is the previous pose, 0.6 m behind.
TEST_F(LocalizerTest, OdometryAtItsOwnRatePredictsTheFrame) {
  for (bool with_odometry : {true, false}) {
    localizer::Config cfg;
    cfg.use_imu = false;
    localizer::Localizer loc(*map_.lookup, cfg);
    if (with_odometry)
      for (double t = -0.037; t < 6.0; t += 0.05) {
        // In the odometry's own frame: the truth moved by 5 m and turned by 1 rad.
        const Pose2 p = compose(Pose2{5, -2, 1}, truth_at(t));
        loc.add_odometry(int64_t(std::llround(t * 1e6)), p);
      }
    loc.set_pose(truth_at(0.0));
    std::vector<localizer::Pose> finals;
    for (int k : {0, 10, 20, 30}) {
      // A planar laser's scan: no sweep to de-skew (the pose is the one at utime).
      SynthOptions so;
      so.seed = uint32_t(k + 1);
      so.noise_sigma = 0.01;
      const FeatureFrame f = synth_frame(*map_.plan, truth_at(0.1 * k), so, int64_t(std::llround(0.1 * k * 1e6)));
      const auto s = loc.process(f, &finals);
      const Pose2 truth = truth_at(0.1 * k);
      const double miss = std::hypot(s.sfr.match.predicted.x - truth.x, s.sfr.match.predicted.y - truth.y);
      if (k == 0) continue;
      if (with_odometry) EXPECT_LT(miss, 0.005) << "frame " << k;
      else EXPECT_GT(miss, 0.3) << "frame " << k;
      EXPECT_EQ(s.sfr.match.status, matcher::FitStatus::kOk) << k << " " << s.sfr.match.text;
    }
  }
}

// A plan that is an occupancy map also says where it is empty. The room rasterised at 5 cm (occupied within half
// a cell diagonal of an element, else free): a frame at its true pose puts almost none of its points in the free
// space; the same frame 0.6 m off puts its unmatched points on empty floor (contradicted > a quarter, the
// published POOR); a whole run with the free space publishes no such POOR. A plan loaded from a map_server file
// carries its free space, a JSON plan none.
TEST_F(LocalizerTest, FreeSpaceOfAnOccupancyMapContradictsAFixOnEmptyFloor) {
  const Box2 box = map_.plan->bounds();
  OccupancyGrid g;
  g.resolution = 0.05;
  g.origin_x = box.min.x() - 1.0;
  g.origin_y = box.min.y() - 1.0;
  g.width = int(std::ceil((box.size().x() + 2.0) / g.resolution));
  g.height = int(std::ceil((box.size().y() + 2.0) / g.resolution));
  g.data.assign(size_t(g.width) * size_t(g.height), 0);
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      const Eigen::Vector2d c = g.cell_centre(i, j);
      for (const auto& e : map_.plan->elements)
        if (distance(e, c) <= 0.5 * std::sqrt(2.0) * g.resolution) g.data[size_t(j) * size_t(g.width) + size_t(i)] = 100;
    }
  const FreeSpace fs(g);
  localizer::Config cfg;
  cfg.free_space = &fs;
  const localizer::Localizer probe(*map_.lookup, cfg);
  const Pose2 truth = truth_at(2.0), off{truth.x + 0.6, truth.y, truth.yaw};
  SynthOptions so;  // one instant (no sweep to de-skew), 1 cm noise
  so.noise_sigma = 0.01;
  const FeatureFrame f = synth_frame(*map_.plan, truth, so);
  const double in_m = cfg.matcher.inlier_m;
  const double at_truth = probe.contradicted(f, truth, matcher::evaluate_fit(*map_.lookup, f, truth, in_m, 1).inlier_ratio);
  const double at_off = probe.contradicted(f, off, matcher::evaluate_fit(*map_.lookup, f, off, in_m, 1).inlier_ratio);
  EXPECT_LT(at_truth, 0.05);
  EXPECT_GT(at_off, 0.25);
  localizer::Localizer loc(*map_.lookup, cfg);
  loc.set_pose(truth_at(0.0));
  std::vector<localizer::Pose> finals;
  int poor_free = 0;
  for (size_t k = 0; k < frames_.size(); ++k) {
    feed_imu(loc, 0.1 * k - 0.1, 0.1 * k + 0.11);
    loc.process(frames_[k], &finals);
    poor_free += loc.uncertainty().text.find("the map says empty") != std::string::npos;
  }
  EXPECT_EQ(poor_free, 0);
  // Loaded from files: the occupancy map keeps its free space.
  const auto dir = std::filesystem::temp_directory_path() / ("fploc_loc_free_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream pgm(dir / "m.pgm", std::ios::binary);
    pgm << "P5\n" << g.width << " " << g.height << "\n255\n";
    for (int row = g.height - 1; row >= 0; --row)  // PGM rows top first; the grid's row 0 is the bottom
      for (int i = 0; i < g.width; ++i) pgm << char(g.at(i, row) == 100 ? 0 : 254);
    std::ofstream(dir / "m.yaml") << "image: m.pgm\nresolution: 0.05\norigin: [" << g.origin_x << ", " << g.origin_y
                                  << ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  }
  const auto from_yaml = matcher::load_localization_map((dir / "m.yaml").string(), {}, "", "annf-exact");
  ASSERT_NE(from_yaml.free_space, nullptr);
  EXPECT_EQ(from_yaml.free_space->free_cells(), fs.free_cells());
  EXPECT_EQ(map_.free_space, nullptr);
  // ... and its cell's position error (a wall somewhere in its 5 cm cell); a drawn plan has none.
  EXPECT_NEAR(from_yaml.map_sigma_m, 0.05 / std::sqrt(12.0), 1e-12);
  EXPECT_EQ(map_.map_sigma_m, 0.0);
  localizer::Config used;
  localizer::use_map(used, from_yaml);
  EXPECT_EQ(used.free_space, from_yaml.free_space.get());
  EXPECT_EQ(used.map_sigma_m, from_yaml.map_sigma_m);
  // A building whose floor is drawn as a map_server map: that floor's map keeps them too, a JSON floor none.
  std::filesystem::copy_file(std::string(FPLOC_SOURCE_DIR) + "/data/plans/room.json", dir / "room.json");
  std::ofstream(dir / "b.pbtxt") << "name: \"b\"\nfloor { name: \"scan\" plan { file: \"m.yaml\" } elevation_m: 0 ceiling_height_m: 3 }\n"
                                 << "floor { name: \"drawn\" plan { file: \"room.json\" } elevation_m: 4 ceiling_height_m: 3 }\n";
  const auto floors = localizer::load_floor_maps((dir / "b.pbtxt").string(), {}, "", "scan", "annf-exact");
  ASSERT_EQ(floors.maps.size(), 2u);
  ASSERT_NE(floors.maps[0].free_space, nullptr);
  EXPECT_EQ(floors.maps[0].free_space->free_cells(), fs.free_cells());
  EXPECT_NEAR(floors.maps[0].map_sigma_m, 0.05 / std::sqrt(12.0), 1e-12);
  EXPECT_EQ(floors.maps[1].free_space, nullptr);
  EXPECT_EQ(floors.maps[1].map_sigma_m, 0.0);
  std::filesystem::remove_all(dir);
}

// The map's own error (Config::map_sigma_m) is in the published covariance and nowhere else: the same run with
// and without it gives the same poses and statuses, and every published covariance differs by exactly
// map_sigma^2 in x and y and (map_sigma / the frame's median point range)^2 in yaw.
TEST_F(LocalizerTest, MapSigmaWidensThePublishedCovarianceOnly) {
  localizer::Config with;
  with.map_sigma_m = 0.05 / std::sqrt(12.0);
  localizer::Localizer a(*map_.lookup, {}), b(*map_.lookup, with);
  a.set_pose(truth_at(0.0));
  b.set_pose(truth_at(0.0));
  std::vector<localizer::Pose> fa, fb;
  int compared = 0;
  for (size_t k = 0; k < frames_.size(); ++k) {
    feed_imu(a, 0.1 * k - 0.1, 0.1 * k + 0.11);
    feed_imu(b, 0.1 * k - 0.1, 0.1 * k + 0.11);
    const auto sa = a.process(frames_[k], &fa), sb = b.process(frames_[k], &fb);
    ASSERT_EQ(sa.latest.has_value(), sb.latest.has_value());
    if (!sa.latest) continue;
    EXPECT_EQ(sa.latest->pose.x, sb.latest->pose.x);
    EXPECT_EQ(sa.latest->pose.yaw, sb.latest->pose.yaw);
    EXPECT_EQ(sa.latest->status, sb.latest->status);
    std::vector<double> r;
    for (const auto& p : frames_[k].points) r.push_back(p.p.norm());
    std::nth_element(r.begin(), r.begin() + std::ptrdiff_t(r.size() / 2), r.end());
    const double s = with.map_sigma_m, syaw = s / std::max(r[r.size() / 2], 1.0);
    const Eigen::Matrix3d d = sb.latest->covariance - sa.latest->covariance;
    EXPECT_NEAR(d(0, 0), s * s, 1e-12);
    EXPECT_NEAR(d(1, 1), s * s, 1e-12);
    EXPECT_NEAR(d(2, 2), syaw * syaw, 1e-15);
    EXPECT_NEAR(d(0, 1), 0.0, 1e-15);
    ++compared;
  }
  EXPECT_GT(compared, 50);
  ASSERT_EQ(fa.size(), fb.size());
  for (size_t i = 0; i < fa.size(); ++i) EXPECT_EQ(fa[i].pose.y, fb[i].pose.y);
}
