// The raster-map localizer on a synthetic occupancy grid: an irregular room (walls, an inner wall, pillars),
// 180-degree scans ray-cast in the grid from a known trajectory, wheel odometry with a scale error and yaw
// drift. Checks the distance field, tracking from the true start, a start 1 m / 10 deg off, and that a scan
// the map cannot explain (a different room) is POOR and keeps the odometry prediction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <random>

#include "fploc/floorplan/distance_field.h"
#include "fploc/laser2d/grid_localizer.h"
#include "../src/field_fit.h"
#include "synthetic_grid.h"

namespace {

using fploc::OccupancyGrid;
using fploc::Pose2;
namespace l2 = fploc::laser2d;

OccupancyGrid make_room(bool other_room = false) {
  OccupancyGrid g = l2::test::blank_grid(300, 200);
  auto occ = [&](double x, double y) { l2::test::occupy(g, x, y); };
  // Outer walls of a 13 x 8 m room.
  if (!other_room)
    for (double t = -0.5; t <= 12.5; t += 0.02) occ(t, -0.5), occ(t, 7.5);
  if (!other_room)
    for (double t = -0.5; t <= 7.5; t += 0.02) occ(-0.5, t), occ(12.5, t);
  if (other_room) {
    for (double t = 2; t <= 6; t += 0.02) occ(t, 3.0);  // one wall elsewhere
    return g;
  }
  // An inner wall with a gap, an alcove, pillars.
  for (double t = 3.0; t <= 7.5; t += 0.02) occ(4.0, t);
  for (double t = -0.5; t <= 1.5; t += 0.02) occ(8.0, t);
  for (double t = 8.0; t <= 10.0; t += 0.02) occ(t, 1.5);
  for (double a = 0; a < 2 * M_PI; a += 0.05) occ(6.5 + 0.2 * std::cos(a), 4.5 + 0.2 * std::sin(a)), occ(10 + 0.15 * std::cos(a), 5 + 0.15 * std::sin(a));
  return g;
}

// 181 beams over 180 degrees, ray-cast to the first occupied cell (max 30 m), noise 1 cm.
std::vector<Eigen::Vector2d> cast(const OccupancyGrid& g, const Pose2& p, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.01);
  std::vector<float> r;
  for (int k = 0; k < 181; ++k) {
    const double d = l2::test::first_hit(g, p.x, p.y, p.yaw - M_PI / 2 + k * M_PI / 180, 30);
    r.push_back(std::isfinite(d) ? float(d + n(rng)) : std::numeric_limits<float>::infinity());
  }
  return l2::scan_points(r, -M_PI / 2, M_PI / 180, 0.1, 30);
}

// n poses from a towards b (b itself not included), the yaw turned the short way.
void append_line(std::vector<Pose2>& t, Pose2 a, Pose2 b, int n) {
  for (int k = 0; k < n; ++k) {
    const double s = double(k) / n;
    t.push_back({a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), a.yaw + s * fploc::wrap_angle(b.yaw - a.yaw)});
  }
}

// A loop through the room: 1 m steps and turns, as the Radish logs' scan spacing.
std::vector<Pose2> trajectory() {
  std::vector<Pose2> t;
  auto add_line = [&](Pose2 a, Pose2 b, int n) { append_line(t, a, b, n); };
  add_line({1, 1, 0}, {7, 1.2, 0}, 8);
  add_line({7, 1.2, 0}, {7, 2.5, M_PI / 2}, 3);
  add_line({7, 2.5, M_PI / 2}, {11, 3, 0.2}, 5);
  add_line({11, 3, 0.2}, {11, 6.5, M_PI / 2}, 5);
  add_line({11, 6.5, M_PI / 2}, {5, 6.2, M_PI}, 8);
  add_line({5, 6.2, M_PI}, {2, 2, -M_PI / 2}, 6);
  return t;
}

// Wheel odometry: increments with a 3 % scale error and 2 deg/m yaw drift, in a frame of its own.
std::vector<Pose2> odometry(const std::vector<Pose2>& truth) {
  std::vector<Pose2> o{{100, -50, 1.0}};
  for (size_t k = 1; k < truth.size(); ++k) {
    Pose2 inc = fploc::between(truth[k - 1], truth[k]);
    const double step = std::hypot(inc.x, inc.y);
    inc.x *= 1.03;
    inc.y *= 1.03;
    inc.yaw += step * 2 * M_PI / 180;
    o.push_back(fploc::compose(o.back(), inc));
  }
  return o;
}

struct TrackRun {
  double rms = 0, max = 0;
  int ok = 0, n = 0;
};

TrackRun track(const Pose2& start) {
  const OccupancyGrid g = make_room();
  auto df = std::make_shared<fploc::DistanceField>(g, 1.0);
  l2::GridLocalizer loc(df);
  loc.set_initial_pose(start);
  std::mt19937 rng(7);
  const auto truth = trajectory();
  const auto odo = odometry(truth);
  TrackRun r;
  double ss = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    const auto res = loc.update(cast(g, truth[k], rng), odo[k]);
    const double e = std::hypot(res.pose.x - truth[k].x, res.pose.y - truth[k].y);
    ss += e * e;
    r.max = std::max(r.max, e);
    r.ok += res.status == l2::GridStatus::kOk;
    ++r.n;
  }
  r.rms = std::sqrt(ss / r.n);
  return r;
}

TEST(DistanceField, ExactWithinTruncation) {
  OccupancyGrid g;
  g.width = 40;
  g.height = 30;
  g.resolution = 0.1;
  g.origin_x = 2;
  g.origin_y = -1;
  g.data.assign(size_t(g.width) * g.height, 0);
  g.data[size_t(10) * g.width + 20] = 100;  // cell (20, 10): centre (4.05, 0.05)
  const fploc::DistanceField df(g, 1.0);
  EXPECT_EQ(df.occupied_cells(), 1u);
  EXPECT_FLOAT_EQ(df.at(20, 10), 0.f);
  EXPECT_NEAR(df.at(23, 14), 0.5, 1e-6);                             // 3-4-5 cells
  EXPECT_FLOAT_EQ(df.at(35, 10), 1.0f);                              // beyond the truncation
  EXPECT_NEAR(df.nearest({4.05 + 0.3, 0.05}), 0.3, 1e-6);
  const Eigen::Vector2d c = df.to_cell({4.05, 0.05});
  EXPECT_NEAR(c.x(), 20, 1e-9);
  EXPECT_NEAR(c.y(), 10, 1e-9);
}

TEST(GridLocalizer, TracksWithDriftingOdometry) {
  const TrackRun r = track({1, 1, 0});
  EXPECT_LT(r.rms, 0.03) << "max " << r.max;
  EXPECT_EQ(r.ok, r.n);
}

TEST(GridLocalizer, StartOneMetreTenDegreesOff) {
  const TrackRun r = track({1 + std::cos(M_PI / 4), 1 + std::sin(M_PI / 4), 10 * M_PI / 180});
  EXPECT_LT(r.rms, 0.03) << "max " << r.max;
  EXPECT_EQ(r.ok, r.n);
}

TEST(GridLocalizer, UnexplainedScanIsPoorAndKeepsTheOdometry) {
  const OccupancyGrid map = make_room(), other = make_room(true);
  l2::GridLocalizerConfig c;
  c.calibrate_odometry = false;  // the raw odometry's prediction (the first good pair would already correct it)
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(map, 1.0), c);
  loc.set_initial_pose({1, 1, 0});
  std::mt19937 rng(3);
  ASSERT_EQ(loc.update(cast(map, {1, 1, 0}, rng), Pose2{0, 0, 0}).status, l2::GridStatus::kOk);
  auto r0 = loc.update(cast(map, {1.5, 1, 0}, rng), Pose2{0.5, 0, 0});
  ASSERT_EQ(r0.status, l2::GridStatus::kOk);
  // The robot drives 1 m on; the scan comes from a room the map does not contain.
  auto r1 = loc.update(cast(other, {2.5, 1, 0}, rng), Pose2{1.5, 0, 0});
  EXPECT_NE(r1.status, l2::GridStatus::kOk);
  const Pose2 pred = fploc::compose(r0.pose, {1, 0, 0});  // the odometry prediction
  EXPECT_NEAR(r1.pose.x, pred.x, 1e-9);
  EXPECT_NEAR(r1.pose.y, pred.y, 1e-9);
  EXPECT_NEAR(r1.pose.yaw, pred.yaw, 1e-9);
  EXPECT_GT(r1.search_xy_m, r0.search_xy_m);  // the uncertainty grew
}

// Kidnapping: after 12 scans the robot is carried 8 poses further along its loop (several metres and a turn
// away) without the odometry knowing. The fits fail, the tracker goes LOST, and the re-acquisition (wide
// search, hypotheses tracked by the odometry, one confirmed over several scans) finds the robot again: the last
// 20 scans are OK and within 5 cm. Without re-acquisition the same run does not recover.
double kidnap_run(bool reacquire, int* reacquired, int* ok_tail, double* tail_max) {
  const OccupancyGrid g = make_room();
  l2::GridLocalizerConfig c;
  c.reacquire = reacquire;
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(g, 1.0), c);
  const auto lap = trajectory();
  std::vector<Pose2> base;
  for (int k = 0; k < 3; ++k) base.insert(base.end(), lap.begin(), lap.end());
  const size_t K = 12, shift = 8;
  std::vector<Pose2> truth(base.begin(), base.begin() + K);
  for (size_t k = K + shift; k < base.size(); ++k) truth.push_back(base[k]);
  // Odometry: the truth's increments, except the kidnap step (the wheels moved one ordinary step).
  std::vector<Pose2> odo{{100, -50, 1.0}};
  for (size_t k = 1; k < truth.size(); ++k)
    odo.push_back(fploc::compose(odo.back(), k == K ? fploc::between(base[K - 1], base[K]) : fploc::between(truth[k - 1], truth[k])));
  loc.set_initial_pose(truth[0]);
  std::mt19937 rng(11);
  *reacquired = 0;
  *ok_tail = 0;
  *tail_max = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    const auto r = loc.update(cast(g, truth[k], rng), odo[k]);
    *reacquired += r.reacquired;
    if (k + 20 >= truth.size()) {
      *ok_tail += r.status == l2::GridStatus::kOk;
      *tail_max = std::max(*tail_max, std::hypot(r.pose.x - truth[k].x, r.pose.y - truth[k].y));
    }
  }
  return 0;
}

TEST(GridLocalizer, ReacquiresAfterAKidnap) {
  int reacq = 0, ok = 0;
  double tail = 0;
  kidnap_run(true, &reacq, &ok, &tail);
  EXPECT_GE(reacq, 1);
  EXPECT_EQ(ok, 20);
  EXPECT_LT(tail, 0.05);
  kidnap_run(false, &reacq, &ok, &tail);
  EXPECT_GT(tail, 0.5) << "the kidnap is recovered without re-acquisition: the test does not test it";
}

TEST(GridLocalizer, ScanPointsDropInvalidAndApplyMount) {
  const std::vector<float> r{1.f, std::numeric_limits<float>::quiet_NaN(), 0.01f, 50.f, 2.f};
  const auto p = l2::scan_points(r, -M_PI / 2, M_PI / 4, 0.1, 40, {0.5, 0, 0});
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR(p[0].x(), 0.5, 1e-9);
  EXPECT_NEAR(p[0].y(), -1, 1e-9);
  EXPECT_NEAR(p[1].x(), 0.5, 1e-9);  // beam 4 at +90 deg, 2 m
  EXPECT_NEAR(p[1].y(), 2, 1e-9);
  // Upside down (rolled 180 deg, as a laser hung under a shelf): the beam at +90 deg looks to the right.
  const auto q = l2::scan_points(r, -M_PI / 2, M_PI / 4, 0.1, 40, {0.5, 0, 0}, true);
  ASSERT_EQ(q.size(), 2u);
  EXPECT_NEAR(q[0].y(), 1, 1e-9);
  EXPECT_NEAR(q[1].x(), 0.5, 1e-9);
  EXPECT_NEAR(q[1].y(), -2, 1e-9);
}

}  // namespace

// Dead reckoning: while the scans are unexplained (POOR) the uncertainty grows with the motion, not per scan:
// a robot that stands still for many scans keeps its window; one that drives widens it. Control: the per-scan
// bases added on every POOR scan (the earlier model) widen it while standing still.
// Tracked once at (1, 1, 0) in the room, then `scans` scans of another room (unexplained), scan k at
// k * step m along x with the odometry saying so; `each` sees every result.
void tracked_then_unexplained(const l2::GridLocalizerConfig& c, int scans, double step,
                              const std::function<void(const l2::GridResult&)>& each) {
  const OccupancyGrid map = make_room(), other = make_room(true);
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(map, 1.0), c);
  loc.set_initial_pose({1, 1, 0});
  std::mt19937 rng(5);
  EXPECT_EQ(loc.update(cast(map, {1, 1, 0}, rng), Pose2{0, 0, 0}).status, l2::GridStatus::kOk);
  for (int k = 1; k <= scans; ++k) {
    const auto r = loc.update(cast(other, {1 + step * k, 1, 0}, rng), Pose2{step * k, 0, 0});
    EXPECT_NE(r.status, l2::GridStatus::kOk);
    each(r);
  }
}

double poor_window_after_standing(bool motion_only, int scans) {
  l2::GridLocalizerConfig c;
  c.dead_reckoning_motion_only = motion_only;
  c.laser_odometry = false;  // the wheels' model (a matched laser step has its own, smaller one)
  double w = 0;
  tracked_then_unexplained(c, scans, 0.0, [&](const l2::GridResult& r) { w = std::sqrt(r.covariance(0, 0)); });
  return w;
}

TEST(GridLocalizer, DeadReckoningUncertaintyGrowsWithMotionOnly) {
  const double w1 = poor_window_after_standing(true, 1), w8 = poor_window_after_standing(true, 8);
  EXPECT_NEAR(w8, w1, 1e-6) << "standing still widened the dead-reckoned uncertainty";
  const double old8 = poor_window_after_standing(false, 8);
  EXPECT_GT(old8, 2 * w1) << "control: the per-scan model should grow while standing";
}

// An odometry turn error beyond the tracking window (csail: 30 deg on a 1 m step): the first fit fails, the
// retry in a window twice as wide finds the pose (>= min_inlier_ratio). Control: without the retry the scan is
// POOR and the estimate the wrong prediction.
l2::GridResult wrong_turn(double retry_factor, const Pose2& truth) {
  const OccupancyGrid map = make_room();
  l2::GridLocalizerConfig c;
  c.retry_window_factor = retry_factor;
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(map, 1.0), c);
  loc.set_initial_pose({1, 1, 0});
  std::mt19937 rng(9);
  EXPECT_EQ(loc.update(cast(map, {1, 1, 0}, rng), Pose2{0, 0, 0}).status, l2::GridStatus::kOk);
  EXPECT_EQ(loc.update(cast(map, {2, 1, 0}, rng), Pose2{1, 0, 0}).status, l2::GridStatus::kOk);
  // The robot drives 1 m on and turns 25 deg; the odometry reports a straight step.
  return loc.update(cast(map, truth, rng), Pose2{2, 0, 0});
}

TEST(GridLocalizer, RetriesAFailedFitInAWiderWindow) {
  const Pose2 truth{3, 1, 25 * M_PI / 180};
  const auto r = wrong_turn(2.0, truth);
  EXPECT_EQ(r.status, l2::GridStatus::kOk);
  EXPECT_LT(std::hypot(r.pose.x - truth.x, r.pose.y - truth.y), 0.05);
  EXPECT_LT(std::abs(fploc::wrap_angle(r.pose.yaw - truth.yaw)), 1 * M_PI / 180);
  const auto c = wrong_turn(1.0, truth);
  EXPECT_NE(c.status, l2::GridStatus::kOk) << "control: the pose was found without the retry; the test does not test it";
}

// Unmapped ground (issue 13, intel scans 889-902: the wheels under-report turns by ~3.5 deg/m and 10 m without
// the map turned that into -43 deg): two laps of the room tracked with odometry whose yaw drifts 4 deg/m and
// whose scale is 4 % short, then the scans stop (nothing in range) for 8 steps while the robot drives on. The
// dead-reckoned pose at the end of that stretch is within 0.4 m / 7 deg of the truth with the calibration
// learnt from the laps; control: with the raw odometry it is off by more than 15 deg.
Pose2 dead_reckoning_error(bool calibrate) {
  const OccupancyGrid g = make_room();
  l2::GridLocalizerConfig c;
  c.calibrate_odometry = calibrate;
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(g, 1.0), c);
  const auto lap = trajectory();
  std::vector<Pose2> truth;
  for (int k = 0; k < 3; ++k) truth.insert(truth.end(), lap.begin(), lap.end());
  const size_t blind_from = 2 * lap.size(), blind_to = blind_from + 8;
  std::vector<Pose2> odo{{100, -50, 1.0}};
  for (size_t k = 1; k < truth.size(); ++k) {
    Pose2 inc = fploc::between(truth[k - 1], truth[k]);
    const double step = std::hypot(inc.x, inc.y);
    inc.x *= 0.96;
    inc.y *= 0.96;
    inc.yaw -= step * 4 * M_PI / 180;
    odo.push_back(fploc::compose(odo.back(), inc));
  }
  loc.set_initial_pose(truth[0]);
  std::mt19937 rng(13);
  Pose2 err;
  for (size_t k = 0; k < blind_to; ++k) {
    const auto r = loc.update(k < blind_from ? cast(g, truth[k], rng) : std::vector<Eigen::Vector2d>{}, odo[k]);
    if (k + 1 == blind_to) {
      EXPECT_NE(r.status, l2::GridStatus::kOk);
      err = {r.pose.x - truth[k].x, r.pose.y - truth[k].y, fploc::wrap_angle(r.pose.yaw - truth[k].yaw)};
    }
  }
  return err;
}

TEST(GridLocalizer, CalibratedOdometryCarriesThroughUnmappedGround) {
  const Pose2 e = dead_reckoning_error(true);
  std::cerr << "calibrated: " << std::hypot(e.x, e.y) << " m " << e.yaw * 180 / M_PI << " deg\n";
  EXPECT_LT(std::hypot(e.x, e.y), 0.4);
  EXPECT_LT(std::abs(e.yaw), 7 * M_PI / 180);
  const Pose2 raw = dead_reckoning_error(false);
  std::cerr << "raw: " << std::hypot(raw.x, raw.y) << " m " << raw.yaw * 180 / M_PI << " deg\n";
  EXPECT_GT(std::abs(raw.yaw), 15 * M_PI / 180) << "control: the raw odometry kept the yaw; the test does not test it";
}

// CPU while re-acquiring: the wide search runs again only after 0.5 m (or 15 deg) of motion since the last one;
// at 10 cm per scan that is every fifth unexplained scan (freiburg-079's 10 Hz scans: 100-400 ms each before).
// Control: with the throttle off it runs on every scan.
int wide_searches(double every_m, int scans) {
  l2::GridLocalizerConfig c;
  c.reacquire_search_every_m = every_m;
  int n = 0;
  tracked_then_unexplained(c, scans, 0.1, [&](const l2::GridResult& r) { n += r.wide_search; });
  return n;
}

TEST(GridLocalizer, WideSearchWhileLostIsThrottledByMotion) {
  EXPECT_LE(wide_searches(0.5, 20), 5);
  EXPECT_GE(wide_searches(0, 20), 15) << "control: without the throttle (nearly) every scan searches";
}

// Re-acquisition is not a lottery (issue 13, seventh pass). Two 1 x 1 m boxes open at the bottom, 1.5 m apart
// (interiors x in [0, 1] and [1.5, 2.5], y in [0, 1]); a robot inside one, heading +y, sees only that box's three
// walls, so its scan fits both boxes equally.
OccupancyGrid boxes(bool second) {
  OccupancyGrid g = l2::test::blank_grid(120, 60);
  auto box = [&](double x0) {
    for (double t = 0; t <= 1.0; t += 0.01) {
      l2::test::occupy(g, x0 - 0.05, t);
      l2::test::occupy(g, x0 + 1.05, t);
      l2::test::occupy(g, x0 - 0.05 + 1.1 * t, 1.05);
    }
  };
  box(0);
  if (second) box(1.5);
  return g;
}

// Started at `start` (+-0.5 m / 5 deg), one scan with no returns (the tracker becomes POOR: re-acquiring), then
// the scan of the robot at (0.5, 0.4) in the first box, plus `clutter` returns 3-4 m away that the map does not
// explain (a weak fit); the odometry reports no motion.
l2::GridResult reacquire_in_boxes(const l2::GridLocalizerConfig& c, bool second, const Pose2& start, int clutter) {
  const OccupancyGrid g = boxes(second);
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(g, 1.0), c);
  loc.set_initial_pose(start);
  EXPECT_EQ(loc.update({}, Pose2{0, 0, 0}).status, l2::GridStatus::kPoor);
  std::mt19937 rng(17);
  auto pts = cast(g, {0.5, 0.4, M_PI / 2}, rng);
  std::uniform_real_distribution<double> a(0.3, M_PI - 0.3), r(3, 4);
  for (int k = 0; k < clutter; ++k) {
    const double ak = a(rng), rk = r(rng);
    pts.emplace_back(rk * std::sin(ak), -rk * std::cos(ak));  // robot frame (x forward = +y in the world)
  }
  return loc.update(pts, Pose2{0, 0, 0});
}

// (2) A scan that fits two places equally, from a dead-reckoned pose midway between them (both within its
// uncertainty): no place is taken, the tracker stays POOR at its prediction. Control: without the rule it
// jumps to one of them (which one is decided by the search's tie-break, i.e. by chance).
TEST(GridLocalizer, ReacquisitionRefusesAScanThatFitsTwoPlaces) {
  l2::GridLocalizerConfig c;
  const Pose2 mid{1.25, 0.4, M_PI / 2};
  const auto r = reacquire_in_boxes(c, true, mid, 0);
  EXPECT_EQ(r.status, l2::GridStatus::kPoor);
  EXPECT_NEAR(r.pose.x, mid.x, 1e-9);
  EXPECT_NEAR(r.pose.y, mid.y, 1e-9);
  c.rival_margin = -1;
  const auto ctl = reacquire_in_boxes(c, true, mid, 0);
  EXPECT_EQ(ctl.status, l2::GridStatus::kOk) << "control: the ambiguous scan was refused without the rule";
  EXPECT_GT(std::abs(ctl.pose.x - mid.x), 0.5);
  // One box only: the same scan is unrivalled and ends POOR at once, in the box.
  c.rival_margin = 0.1;
  const auto one = reacquire_in_boxes(c, false, mid, 0);
  EXPECT_EQ(one.status, l2::GridStatus::kOk);
  EXPECT_LT(std::hypot(one.pose.x - 0.5, one.pose.y - 0.4), 0.05);
}

// After LOST, the track is published OK again once confirm_scans fits in a row explain on average at least
// confirm_inlier_ratio of the scans; a track that keeps explaining too little stays POOR although it is followed.
// After a POOR stretch shorter than LOST the first good fit is OK.
TEST(GridLocalizer, TrackIsPublishedOkAgainOnlyOnceReconfirmedAfterLost) {
  const int lost_after = l2::GridLocalizerConfig{}.lost_after, cs = l2::GridLocalizerConfig{}.confirm_scans;
  for (const auto& [unexplained, clutter] :
       std::vector<std::pair<int, double>>{{lost_after + 2, 0.0}, {lost_after + 2, 0.45}, {2, 0.0}}) {
    const OccupancyGrid map = make_room(), other = make_room(true);
    l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(map, 1.0));
    loc.set_initial_pose({1, 1, 0});
    std::mt19937 rng(5), crng(3);
    std::uniform_real_distribution<double> u(0, 1);
    ASSERT_EQ(loc.update(cast(map, {1, 1, 0}, rng), Pose2{0, 0, 0}).status, l2::GridStatus::kOk);
    l2::GridStatus last = l2::GridStatus::kOk;
    for (int k = 0; k < unexplained; ++k) last = loc.update(cast(other, {1, 1, 0}, rng), Pose2{0, 0, 0}).status;
    ASSERT_EQ(last, unexplained > lost_after ? l2::GridStatus::kLost : l2::GridStatus::kPoor);
    std::vector<l2::GridStatus> st;
    for (int k = 0; k < 8; ++k) {
      auto pts = cast(map, {1 + 0.05 * k, 1, 0}, rng);
      for (auto& p : pts)
        if (u(crng) < clutter) p = {1 + 2 * u(crng), 2 * u(crng) - 1};
      const auto r = loc.update(pts, Pose2{0.05 * k, 0, 0});
      EXPECT_LT(std::hypot(r.pose.x - (1 + 0.05 * k), r.pose.y - 1), 0.08) << clutter << " " << k;
      st.push_back(r.status);
    }
    for (int k = 0; k < 8; ++k) {
      const auto tag = ::testing::Message() << unexplained << " unexplained, clutter " << clutter << ", scan " << k;
      if (unexplained <= lost_after)  // POOR only, clean scans: OK from the first fit
        EXPECT_EQ(st[k], l2::GridStatus::kOk) << tag;
      else if (clutter == 0)  // clean scans after LOST: POOR until confirm_scans fits, then OK
        EXPECT_EQ(st[k], k + 1 < cs ? l2::GridStatus::kPoor : l2::GridStatus::kOk) << tag;
      else  // ~half the scan unexplained: followed, never re-confirmed
        EXPECT_EQ(st[k], l2::GridStatus::kPoor) << tag;
    }
  }
}

// (1) A weak fit (~47 % of the returns explained: the box plus clutter) 0.6 m from the dead-reckoned pose is
// within the accumulated uncertainty (0.5 m: 1.2 sigma) but beyond what one step's odometry can have got wrong
// (5 cm): it is not followed, the prediction is kept. 3 cm away it is followed. Control: without the rule the
// 0.6 m correction is taken.
TEST(GridLocalizer, WeakFitCorrectsOnlyOneStepOfDeadReckoning) {
  l2::GridLocalizerConfig c;
  const Pose2 far{1.1, 0.4, M_PI / 2}, close{0.53, 0.4, M_PI / 2};
  const auto r = reacquire_in_boxes(c, false, far, 200);
  ASSERT_GT(r.inlier_ratio, c.min_inlier_ratio_near);
  ASSERT_LT(r.inlier_ratio, c.min_inlier_ratio);
  EXPECT_EQ(r.status, l2::GridStatus::kPoor);
  EXPECT_NEAR(r.pose.x, far.x, 1e-9);
  const auto n = reacquire_in_boxes(c, false, close, 200);
  EXPECT_EQ(n.status, l2::GridStatus::kPoor);
  EXPECT_LT(std::hypot(n.pose.x - 0.5, n.pose.y - 0.4), 0.02);
  c.weak_follow_step_only = false;
  const auto ctl = reacquire_in_boxes(c, false, far, 200);
  EXPECT_LT(std::hypot(ctl.pose.x - 0.5, ctl.pose.y - 0.4), 0.05) << "control: the weak fit was not followed without the rule";
}

namespace {

// Every scan of the loop above, with a given config; `clutter` replaces that share of each scan's returns
// by points 1-3 m in front of the robot's left half, where the map has nothing (people, furniture).
std::vector<l2::GridResult> track_all(const l2::GridLocalizerConfig& c, double clutter = 0) {
  const OccupancyGrid g = make_room();
  auto df = std::make_shared<fploc::DistanceField>(g, 1.0);
  l2::GridLocalizer loc(df, c);
  loc.set_initial_pose({1, 1, 0});
  std::mt19937 rng(7), crng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const auto truth = trajectory();
  const auto odo = odometry(truth);
  std::vector<l2::GridResult> out;
  for (size_t k = 0; k < truth.size(); ++k) {
    auto pts = cast(g, truth[k], rng);
    for (size_t i = 0; i < pts.size(); ++i)
      if (u(crng) < clutter) {
        const double a = u(crng) * M_PI / 2, r = 1 + 2 * u(crng);
        pts[i] = {r * std::cos(a), r * std::sin(a)};
      }
    out.push_back(loc.update(pts, odo[k]));
  }
  return out;
}

TEST(GridLocalizer, PublishedCovarianceHoldsTheMapsCellAndLeavesTheTrackAlone) {
  l2::GridLocalizerConfig fit_only;
  fit_only.map_sigma_cells = 0;
  const auto a = track_all(fit_only), b = track_all({});
  ASSERT_EQ(a.size(), b.size());
  const double cell = 0.05 / std::sqrt(12.0);  // the synthetic grid's 5 cm cell, uniform within it
  for (size_t k = 0; k < a.size(); ++k) {
    // The track is the same to the last bit: the map's share is published, not fed back.
    EXPECT_EQ(a[k].pose.x, b[k].pose.x) << k;
    EXPECT_EQ(a[k].pose.yaw, b[k].pose.yaw) << k;
    EXPECT_EQ(a[k].status, b[k].status) << k;
    const Eigen::Matrix3d d = b[k].covariance - a[k].covariance;
    EXPECT_NEAR(d(0, 0), cell * cell, 1e-12) << k;
    EXPECT_NEAR(d(1, 1), cell * cell, 1e-12) << k;
    EXPECT_EQ(d(0, 1), 0) << k;
    // In yaw: the cell over the scan's median range (the room's walls are 0.5-13 m away).
    EXPECT_GT(d(2, 2), std::pow(cell / 13, 2)) << k;
    EXPECT_LT(d(2, 2), std::pow(cell / 1.0, 2)) << k;
  }
  // The fit alone typically claims less than the cell in x: that is what the map's share corrects.
  std::vector<double> fit_xx;
  for (const auto& r : a)
    if (r.status == l2::GridStatus::kOk) fit_xx.push_back(r.covariance(0, 0));
  ASSERT_FALSE(fit_xx.empty());
  std::nth_element(fit_xx.begin(), fit_xx.begin() + fit_xx.size() / 2, fit_xx.end());
  EXPECT_LT(fit_xx[fit_xx.size() / 2], cell * cell);
}

TEST(GridLocalizer, WeakFitIsFollowedButPublishedPoor) {
  // 55 % of every scan is clutter the map does not explain: the fits are weak (inliers 35-50 %), near the
  // odometry's prediction, so the tracker follows them; published, they are POOR, not OK.
  l2::GridLocalizerConfig old_rule;
  old_rule.weak_fit_is_poor = false;
  const auto a = track_all(old_rule, 0.55), b = track_all({}, 0.55);
  const auto truth = trajectory();
  int weak = 0, weak_ok_before = 0, weak_ok_now = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].pose.x, b[k].pose.x) << k;  // the same track either way
    if (b[k].inlier_ratio > 0 && b[k].inlier_ratio < l2::GridLocalizerConfig{}.min_inlier_ratio) {
      ++weak;
      weak_ok_before += a[k].status == l2::GridStatus::kOk;
      weak_ok_now += b[k].status == l2::GridStatus::kOk;
    }
    EXPECT_LT(std::hypot(b[k].pose.x - truth[k].x, b[k].pose.y - truth[k].y), 0.15) << k;
  }
  std::cout << "weak fits " << weak << " of " << b.size() << ", published OK before " << weak_ok_before
            << ", now " << weak_ok_now << "\n";
  EXPECT_GE(weak, 5);
  EXPECT_GT(weak_ok_before, 0);  // the old rule published them OK
  EXPECT_EQ(weak_ok_now, 0);
}

}  // namespace

// Laser odometry (laser_odometry.h): the loop through the room with wheels 3 % long and drifting 2 deg/m; the
// increments the scans give, chained from the start, end within 15 cm / 1.5 deg of the truth after the loop
// (~40 m), where the wheels' chain is off by more than 0.5 m and 20 deg (control). A scan with nothing in it
// gives no increment (the caller keeps the wheels').
TEST(LaserOdometry, ChainedIncrementsDriftFarLessThanTheWheels) {
  const OccupancyGrid g = make_room();
  const auto truth = trajectory();
  const auto odo = odometry(truth);
  std::mt19937 rng(11);
  l2::LaserOdometry lo;
  Pose2 laser = truth[0], wheels = truth[0];
  int matched = 0;
  double travelled = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    const Pose2 inc = k ? fploc::between(odo[k - 1], odo[k]) : Pose2{};
    const double step = std::hypot(inc.x, inc.y);
    travelled += step;
    const auto s = lo.update(cast(g, truth[k], rng), inc, 0.05 + 0.3 * step, 2 * M_PI / 180 + 0.3 * std::abs(inc.yaw));
    if (k == 0) {
      EXPECT_FALSE(s) << "the first scan only starts the local map";
      continue;
    }
    wheels = fploc::compose(wheels, inc);
    laser = fploc::compose(laser, s ? s->increment : inc);
    matched += bool(s);
  }
  const Pose2& t = truth.back();
  const double el = std::hypot(laser.x - t.x, laser.y - t.y), ew = std::hypot(wheels.x - t.x, wheels.y - t.y);
  std::cerr << "over " << travelled << " m: laser " << el << " m " << fploc::wrap_angle(laser.yaw - t.yaw) * 180 / M_PI
            << " deg (" << matched << " of " << truth.size() - 1 << " steps matched), wheels " << ew << " m "
            << fploc::wrap_angle(wheels.yaw - t.yaw) * 180 / M_PI << " deg\n";
  EXPECT_GE(matched, int(truth.size()) - 3);
  EXPECT_LT(el, 0.15);
  EXPECT_LT(std::abs(fploc::wrap_angle(laser.yaw - t.yaw)), 1.5 * M_PI / 180);
  EXPECT_GT(ew, 0.5) << "control: the wheels did not drift; the test does not test the laser odometry";
  EXPECT_GT(std::abs(fploc::wrap_angle(wheels.yaw - t.yaw)), 20 * M_PI / 180);
  EXPECT_FALSE(lo.update({}, Pose2{}, 0.05, 0.03));
}

// The same loop against a map that holds one wall of the room only (the rest of the building unmapped): every
// scan after the first is POOR or LOST and the pose is dead-reckoned. With the laser odometry the pose at the
// end of the loop is within 0.3 m / 3 deg of the truth; with the wheels alone (3 % long, 2 deg/m) more than
// 1 m off (control).
Pose2 dead_reckoned_through_unmapped_room(bool laser) {
  const OccupancyGrid world = make_room(), map = make_room(true);
  l2::GridLocalizerConfig c;
  c.laser_odometry = laser;
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(map, 1.0), c);
  const auto truth = trajectory();
  const auto odo = odometry(truth);
  loc.set_initial_pose(truth[0]);
  std::mt19937 rng(17);
  l2::GridResult r;
  int laser_steps = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    r = loc.update(cast(world, truth[k], rng), odo[k]);
    if (k > 0) {
      EXPECT_NE(r.status, l2::GridStatus::kOk) << "scan " << k << ": the one-wall map explained it";
    }
    laser_steps += r.laser_step;
  }
  if (laser) {
    EXPECT_GE(laser_steps, int(truth.size()) - 3);
  }
  const Pose2& t = truth.back();
  return {r.pose.x - t.x, r.pose.y - t.y, fploc::wrap_angle(r.pose.yaw - t.yaw)};
}

TEST(GridLocalizer, LaserOdometryCarriesThroughAnUnmappedRoom) {
  const Pose2 e = dead_reckoned_through_unmapped_room(true);
  std::cerr << "laser odometry: " << std::hypot(e.x, e.y) << " m " << e.yaw * 180 / M_PI << " deg\n";
  EXPECT_LT(std::hypot(e.x, e.y), 0.3);
  EXPECT_LT(std::abs(e.yaw), 3 * M_PI / 180);
  const Pose2 w = dead_reckoned_through_unmapped_room(false);
  std::cerr << "wheels: " << std::hypot(w.x, w.y) << " m " << w.yaw * 180 / M_PI << " deg\n";
  EXPECT_GT(std::hypot(w.x, w.y), 1.0) << "control: the wheels kept the pose; the test does not test the laser odometry";
}

// A hypothesis far beyond what dead reckoning allows needs travel to be taken (freiburg-079 scan 4150: while the
// robot turned in place in a room the map covers in part, an aliased room 4.4 m away kept fitting and was
// taken). The map holds one box (x in [6, 7], open at the bottom); the tracker starts at (0.5, 0.4), 6 m to its
// left. (1) The robot is in an unmapped box of the same shape at the start pose and turns back and forth in
// place: every scan fits the mapped box as well as its own. With the rule the tracker stays where it is
// (dead-reckoned, never OK); control (the bound off): it is carried to the mapped box. (2) The robot is in the
// mapped box (a start 6 m off) and drives back and forth: the far hypothesis keeps matching over
// far_confirm_travel_m of travel and is taken; control (-1: never), it is not.
struct AliasRun {
  int ok = 0;
  double max_x = 0;  // the largest x the tracker published
};
AliasRun run_in_box(const l2::GridLocalizerConfig& c, bool in_mapped_box, int scans) {
  OccupancyGrid world = l2::test::blank_grid(200, 60), map = l2::test::blank_grid(200, 60);
  auto box = [](OccupancyGrid& g, double x0) {
    for (double t = 0; t <= 1.0; t += 0.01) {
      l2::test::occupy(g, x0 - 0.05, t);
      l2::test::occupy(g, x0 + 1.05, t);
      l2::test::occupy(g, x0 - 0.05 + 1.1 * t, 1.05);
    }
  };
  box(world, in_mapped_box ? 6 : 0);
  box(map, 6);
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(map, 1.0), c);
  loc.set_initial_pose({0.5, 0.4, M_PI / 2});
  std::mt19937 rng(23);
  AliasRun out;
  for (int k = 0; k < scans; ++k) {
    // Turning in place (+-20 deg), or driving 0.1 m per scan between y = 0.2 and 0.7 in the mapped box.
    const Pose2 t = in_mapped_box ? Pose2{6.5, 0.2 + 0.1 * std::abs((k + 5) % 10 - 5), M_PI / 2}
                                  : Pose2{0.5, 0.4, M_PI / 2 + 0.35 * std::sin(k / 3.0)};
    const auto r = loc.update(cast(world, t, rng), Pose2{t.y, 0, t.yaw});  // wheels: the truth's increments
    out.ok += r.status == l2::GridStatus::kOk;
    out.max_x = std::max(out.max_x, r.pose.x);
  }
  return out;
}

TEST(GridLocalizer, FarHypothesisNeedsTravelToBeTaken) {
  l2::GridLocalizerConfig c;
  ASSERT_GT(c.confirm_within_sigmas, 0);
  // Test time (every unmatched scan searches wide, 0.4-1 s here): LOST after 3 scans, then 5 to confirm (control);
  // the wide search over the map's extent and +-30 deg.
  c.lost_after = 3;
  c.reacquire_xy_m = 7;
  c.reacquire_yaw_rad = 30 * M_PI / 180;
  const AliasRun r = run_in_box(c, false, 14);
  EXPECT_EQ(r.ok, 0);
  EXPECT_LT(r.max_x, 1.0) << "carried to the aliased box while turning in place";
  const AliasRun drive = run_in_box(c, true, 18);
  EXPECT_GT(drive.max_x, 6.0) << "the robot driving in the mapped box was not found";
  EXPECT_GE(drive.ok, 2);
  auto c0 = c;
  c0.confirm_within_sigmas = 0;
  const AliasRun ctl = run_in_box(c0, false, 14);
  EXPECT_GT(ctl.max_x, 6.0) << "control: the aliased box was not taken without the bound; the test tests nothing";
  c.far_confirm_travel_m = -1;
  const AliasRun never = run_in_box(c, true, 18);
  EXPECT_LT(never.max_x, 1.0) << "control: found without the travel rule; the test does not test it";
}

// The refinement's robust loss, alone (no search, no tracking): a scan of the room at a known pose, the map's
// walls hit exactly (points on the occupied cells' centre lines), plus 40 returns of structure the map lacks, 30 cm
// in front of the east wall. Huber gives each of those a constant pull towards the wall; Cauchy's influence falls
// off with the residual (its pull at 6 sigma is 0.16 of Huber's), Tukey's to nothing.
TEST(FieldFit, RedescendingLossesPullLessTowardsUnmappedStructure) {
  const OccupancyGrid map = make_room();
  auto df = std::make_shared<fploc::DistanceField>(map, 1.0);
  const l2::detail::InterpolatedField field(df);
  const Pose2 truth{9.5, 3.5, 0.1};
  std::vector<Eigen::Vector2d> world;  // wall cell centres: east wall x = 12.525, south y = -0.475, north y = 7.525
  for (double y = 0.0; y <= 7.0; y += 0.1) world.push_back({12.525, y});
  for (double x = 9.0; x <= 12.0; x += 0.1) world.push_back({x, -0.475}), world.push_back({x, 7.525});
  for (double y = 2.5; y <= 4.5; y += 0.05) world.push_back({12.225, y});  // 40 unmapped returns
  const double c = std::cos(truth.yaw), s = std::sin(truth.yaw);
  std::vector<Eigen::Vector2d> pts;  // in the robot frame
  for (const auto& w : world) {
    const Eigen::Vector2d d = w - Eigen::Vector2d(truth.x, truth.y);
    pts.push_back({c * d.x() + s * d.y(), -s * d.x() + c * d.y()});
  }
  auto shift = [&](l2::FitLoss loss) {
    l2::detail::FieldFitOptions o;
    o.loss = loss;
    double x[3] = {truth.x, truth.y, truth.yaw}, cost = 0;
    l2::detail::refine_on_field(field, o, pts, truth, 10.0, 1.0, x, &cost, nullptr);  // a prior that holds nothing
    return std::hypot(x[0] - truth.x, x[1] - truth.y);
  };
  const double huber = shift(l2::FitLoss::kHuber), cauchy = shift(l2::FitLoss::kCauchy);
  const double tukey = shift(l2::FitLoss::kTukey);
  std::cout << "shift by the unmapped returns: Huber " << huber * 100 << " cm, Cauchy " << cauchy * 100 << " cm, Tukey "
            << tukey * 100 << " cm\n";
  EXPECT_GT(huber, 0.01);
  EXPECT_LT(cauchy, 0.6 * huber);
  EXPECT_LT(tukey, 0.1 * huber);
}

// Global localization (start_global: no start pose). On the irregular room the whole-map search proposes
// several places, the odometry and each place's own fit keep only the right one, and it is taken: the first OK
// pose is the truth's and no pose is published OK anywhere else. On a room with point symmetry (every pose has a
// twin rotated 180 degrees about the centre that sees the same scan) no place can dominate: nothing is OK. The
// control run (the rival rules off: global_confirm_margin -1, global_confirm_outlier_ratio 0) does publish OK there
// (at whichever twin leads by chance): the symmetric case fails without the rules.
namespace {

// A 12 x 8 m room symmetric about its centre (5.5, 3.5): every cell drawn is drawn with its point mirror.
OccupancyGrid make_symmetric_room() {
  OccupancyGrid g = l2::test::blank_grid(300, 200);  // x -1 .. 14, y -1 .. 9: the centre is the cell corner (130, 90)
  auto occ = [&](double x, double y) {
    int i, j;
    if (!l2::test::cell_of(g, x, y, &i, &j)) return;
    g.data[size_t(j) * g.width + i] = 100;
    g.data[size_t(179 - j) * g.width + size_t(259 - i)] = 100;
  };
  for (double t = -0.5; t <= 11.5; t += 0.02) occ(t, -0.5);
  for (double t = -0.5; t <= 7.5; t += 0.02) occ(-0.5, t);
  for (double t = 4.0; t <= 7.5; t += 0.02) occ(3.5, t);      // an inner wall from the top wall (and its mirror)
  for (double t = 0.0; t <= 1.5; t += 0.02) occ(t, 5.0);      // an alcove on the left
  for (double a = 0; a < 2 * M_PI; a += 0.05) occ(6.5 + 0.2 * std::cos(a), 5.0 + 0.2 * std::sin(a));  // a pillar
  return g;
}

std::vector<Pose2> symmetric_room_path() {
  std::vector<Pose2> t;
  auto add_line = [&](Pose2 a, Pose2 b, int n) { append_line(t, a, b, n); };
  add_line({1, 1, 0}, {6, 1, 0}, 7);
  add_line({6, 1, 0}, {6, 3.5, M_PI / 2}, 4);
  add_line({6, 3.5, M_PI / 2}, {9, 3.5, 0}, 4);
  add_line({9, 3.5, 0}, {10, 6, M_PI / 2}, 4);
  add_line({10, 6, M_PI / 2}, {5, 6, M_PI}, 7);
  return t;
}

struct GlobalRun {
  int ok = 0, wrong_ok = 0, first_ok = -1;
  double first_ok_err_m = 0, first_ok_err_deg = 0, last_err_m = 0;
  int max_hypotheses = 0;
};

GlobalRun global_run(const OccupancyGrid& g, const std::vector<Pose2>& truth, l2::GridLocalizerConfig c) {
  l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(g, 1.0), c);
  loc.set_free_space(g);
  loc.start_global();
  const auto odo = odometry(truth);
  std::mt19937 rng(5);
  GlobalRun r;
  for (size_t k = 0; k < truth.size(); ++k) {
    const auto res = loc.update(cast(g, truth[k], rng), odo[k]);
    const double e = std::hypot(res.pose.x - truth[k].x, res.pose.y - truth[k].y);
    const double ey = std::abs(fploc::wrap_angle(res.pose.yaw - truth[k].yaw)) * 180 / M_PI;
    r.max_hypotheses = std::max(r.max_hypotheses, res.hypotheses);
    if (res.status != l2::GridStatus::kOk) {
      EXPECT_TRUE(res.status == l2::GridStatus::kLost || res.status == l2::GridStatus::kPoor);
      continue;
    }
    ++r.ok;
    r.wrong_ok += e > 0.3;
    if (r.first_ok < 0) r.first_ok = int(k), r.first_ok_err_m = e, r.first_ok_err_deg = ey;
    r.last_err_m = e;
  }
  return r;
}

}  // namespace

TEST(GridLocalizer, GlobalStartLocksOnAnAsymmetricRoom) {
  const auto lap = trajectory();
  const GlobalRun r = global_run(make_room(), lap, {});
  std::cout << "first OK at scan " << r.first_ok << " (" << r.first_ok_err_m << " m, " << r.first_ok_err_deg
            << " deg off), " << r.ok << " OK of " << lap.size() << ", at most " << r.max_hypotheses << " places\n";
  ASSERT_GE(r.first_ok, 0) << "never locked";
  EXPECT_LE(r.first_ok, 12);  // 5 scans and 1 m at least; the room tells its places apart within a few more
  EXPECT_LT(r.first_ok_err_m, 0.3);
  EXPECT_LT(r.first_ok_err_deg, 5.0);
  EXPECT_EQ(r.wrong_ok, 0);
  EXPECT_LT(r.last_err_m, 0.05);
  EXPECT_GE(r.ok, int(lap.size()) - r.first_ok - 2);
  EXPECT_GE(r.max_hypotheses, 2);  // it did have rivals to rule out
}

TEST(GridLocalizer, GlobalStartStaysLostOnASymmetricRoom) {
  const OccupancyGrid g = make_symmetric_room();
  const auto path = symmetric_room_path();
  const GlobalRun r = global_run(g, path, {});
  EXPECT_EQ(r.ok, 0) << "first OK at scan " << r.first_ok << ", " << r.first_ok_err_m << " m off";
  EXPECT_GE(r.max_hypotheses, 2);
  // Control: without the rival rule one of the twins is taken.
  l2::GridLocalizerConfig weak;
  weak.global_confirm_margin = -1;
  weak.global_confirm_outlier_ratio = 0;
  const GlobalRun w = global_run(g, path, weak);
  std::cout << "symmetric room: " << r.ok << " OK (at most " << r.max_hypotheses << " places); control: first OK at scan "
            << w.first_ok << ", " << w.first_ok_err_m << " m off, " << w.wrong_ok << " wrong OK of " << w.ok << "\n";
  EXPECT_GT(w.ok, 0) << "the control never locked: the symmetric room does not test the rule";
}

// The whole-map search's time budget (global_budget_s, in the scans' time): on the symmetric room no place can be
// taken, so without a budget every scan searches the whole map for ever. With 10 s (scans 1 s apart) the search runs
// while the elapsed time is within the budget (telemetry: global_elapsed_s), then gives up: LOST, global_gave_up, no
// whole-map search on later scans; a given pose starts tracking again. Scans without a stamp, or budget 0: no budget.
TEST(GridLocalizer, GlobalSearchGivesUpAfterItsBudget) {
  const OccupancyGrid g = make_symmetric_room();
  std::vector<Pose2> path = symmetric_room_path();
  const auto back = symmetric_room_path();
  path.insert(path.end(), back.rbegin(), back.rend());  // there and back: 2 x 26 scans
  const auto odo = odometry(path);
  auto run = [&](double budget_s, bool stamps, int* searched, int* gave_up_at) {
    l2::GridLocalizerConfig c;
    c.global_budget_s = budget_s;
    l2::GridLocalizer loc(std::make_shared<fploc::DistanceField>(g, 1.0), c);
    loc.set_free_space(g);
    loc.start_global();
    std::mt19937 rng(5);
    *searched = 0;
    *gave_up_at = -1;
    for (size_t k = 0; k < path.size(); ++k) {
      const auto pts = cast(g, path[k], rng);
      const auto res = stamps ? loc.update(pts, odo[k], 1000.0 + double(k)) : loc.update(pts, odo[k]);
      EXPECT_NE(res.status, l2::GridStatus::kOk) << k;
      *searched += res.wide_search;
      if (res.global) EXPECT_NEAR(res.global_elapsed_s, stamps ? double(k) : 0.0, 1e-9) << k;
      if (res.global_gave_up && *gave_up_at < 0) *gave_up_at = int(k);
      if (*gave_up_at >= 0) {
        EXPECT_TRUE(res.global_gave_up) << k;  // it stays given up
        EXPECT_FALSE(res.global) << k;
        EXPECT_EQ(res.status, l2::GridStatus::kLost) << k;
        EXPECT_EQ(res.hypotheses, 0) << k;
      }
    }
    // A given pose: tracking again.
    loc.set_initial_pose(path.back());
    const auto res = loc.update(cast(g, path.back(), rng), odo.back(), 2000.0);
    EXPECT_FALSE(res.global_gave_up);
    EXPECT_EQ(res.status, l2::GridStatus::kOk);
  };
  int searched = 0, gave_up_at = 0;
  run(10.0, true, &searched, &gave_up_at);
  EXPECT_EQ(gave_up_at, 11);  // elapsed 11 s > 10 s: no search on that scan
  EXPECT_EQ(searched, 11);
  run(0.0, true, &searched, &gave_up_at);  // no budget: every scan searched
  EXPECT_EQ(gave_up_at, -1);
  EXPECT_EQ(searched, int(path.size()));
  run(10.0, false, &searched, &gave_up_at);  // no stamps: no budget
  EXPECT_EQ(gave_up_at, -1);
  EXPECT_EQ(searched, int(path.size()));
}
