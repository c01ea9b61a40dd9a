#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "fploc/eval/eval.h"

using namespace fploc;
using namespace fploc::eval;

namespace {
// A wavy loop at 10 Hz with changing heading (so rotations matter).
Trajectory loop(int n = 300, double dt = 0.1) {
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    const double s = i * dt;
    t.push_back(StampedPose::from_rpy(100.0 + s, {3 * std::cos(0.2 * s), 2 * std::sin(0.2 * s), 0.1 * std::sin(s)},
                                      0.02 * std::sin(s), 0.01 * std::cos(s), 0.2 * s + M_PI / 2));
  }
  return t;
}
Trajectory transformed(const Trajectory& t, const Eigen::Isometry3d& T) {
  Trajectory o;
  for (const auto& p : t) o.push_back(StampedPose::from(p.t, T * p.iso()));
  return o;
}
}  // namespace

TEST(Associate, MatchesWithinMaxDtOnce) {
  auto gt = loop(50);
  auto est = gt;
  for (auto& p : est) p.t += 0.005;
  EXPECT_EQ(associate(gt, est, 0.02).size(), 50u);
  EXPECT_EQ(associate(gt, est, 0.001).size(), 0u);
  EXPECT_EQ(associate(gt, est, 0.001, -0.005).size(), 50u);  // offset compensates
  // Two estimates near one gt pose: only the closer one is used.
  Trajectory g1{gt[0]}, e2{gt[0], gt[0]};
  e2[0].t += 0.01;
  e2[1].t += 0.002;
  const auto p = associate(g1, e2, 0.02);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].second, 1u);
}

TEST(Ate, IdenticalIsZero) {
  const auto gt = loop();
  const auto pairs = associate(gt, gt);
  ASSERT_EQ(pairs.size(), gt.size());
  const auto a = ate(gt, gt, pairs);
  EXPECT_EQ(a.trans.rmse, 0.0);
  EXPECT_EQ(a.trans.max, 0.0);
  EXPECT_NEAR(rpe(gt, gt, pairs).trans.mean, 0.0, 1e-12);
}

TEST(Ate, KnownOffsetWithoutAlignment) {
  const auto gt = loop();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3, -0.4, 0.0);
  const auto est = transformed(gt, T);
  const auto pairs = associate(gt, est);
  const auto a = ate(gt, est, pairs, Align::None);
  EXPECT_NEAR(a.trans.rmse, 0.5, 1e-9);
  EXPECT_NEAR(a.trans.mean, 0.5, 1e-9);
  // A global offset leaves relative motion untouched.
  EXPECT_NEAR(rpe(gt, est, pairs).trans.mean, 0.0, 1e-9);
  // Alignment removes it.
  EXPECT_NEAR(ate(gt, est, pairs, Align::SE3).trans.rmse, 0.0, 1e-6);
  EXPECT_NEAR(ate(gt, est, pairs, Align::SE2).trans.rmse, 0.0, 1e-6);
}

TEST(Ate, RotationAboutZIsRemovedBySe2AndSe3) {
  const auto gt = loop();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1, 2, 0);
  const auto est = transformed(gt, T);
  const auto pairs = associate(gt, est);
  EXPECT_GT(ate(gt, est, pairs, Align::None).trans.rmse, 0.5);
  const auto a2 = ate(gt, est, pairs, Align::SE2);
  EXPECT_NEAR(a2.trans.rmse, 0.0, 1e-6);
  EXPECT_TRUE(a2.S.isApprox(T.inverse(), 1e-6));
  EXPECT_NEAR(ate(gt, est, pairs, Align::SE3).trans.rmse, 0.0, 1e-6);
}

TEST(Ate, StatisticsOfKnownErrors) {
  const auto s = summarize({3, 4, 0, 5});
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt((9 + 16 + 0 + 25) / 4.0));
  EXPECT_DOUBLE_EQ(s.median, 3.5);
  EXPECT_DOUBLE_EQ(s.max, 5.0);
  EXPECT_DOUBLE_EQ(s.min, 0.0);
}

TEST(Rpe, ScaledMotionGivesKnownDrift) {
  // gt moves 1 m/s along x; the estimate 1.1 m/s: over 1 s the relative error is 0.1 m.
  Trajectory gt, est;
  for (int i = 0; i <= 100; ++i) {
    const double t = 0.1 * i;
    gt.push_back(StampedPose::from_rpy(t, {t, 0, 0}, 0, 0, 0));
    est.push_back(StampedPose::from_rpy(t, {1.1 * t, 0, 0}, 0, 0, 0));
  }
  const auto pairs = associate(gt, est);
  const auto r = rpe(gt, est, pairs, 1.0);
  EXPECT_EQ(r.trans.n, 91u);  // pairs k with a partner 1 s later
  EXPECT_NEAR(r.trans.mean, 0.1, 1e-9);
  EXPECT_NEAR(r.trans.rmse, 0.1, 1e-9);
  EXPECT_NEAR(r.rot_deg.mean, 0.0, 1e-9);
  const auto rf = rpe(gt, est, pairs, 1.0, true);  // per frame: 0.01 m
  EXPECT_EQ(rf.trans.n, 100u);
  EXPECT_NEAR(rf.trans.mean, 0.01, 1e-9);
}

TEST(Rpe, YawRateErrorShowsInRotationAndTranslation) {
  // Both turn on the spot; the estimate turns 2 deg/s more: rotational RPE over 1 s = 2 deg.
  Trajectory gt, est;
  for (int i = 0; i <= 50; ++i) {
    const double t = 0.1 * i;
    gt.push_back(StampedPose::from_rpy(t, {0, 0, 0}, 0, 0, 0.1 * t));
    est.push_back(StampedPose::from_rpy(t, {0, 0, 0}, 0, 0, (0.1 + 2.0 * M_PI / 180.0) * t));
  }
  const auto r = rpe(gt, est, associate(gt, est), 1.0);
  EXPECT_NEAR(r.rot_deg.mean, 2.0, 1e-6);
  EXPECT_NEAR(r.trans.mean, 0.0, 1e-9);
}

TEST(Tum, RoundTripIsByteIdentical) {
  const auto dir = std::filesystem::temp_directory_path() / ("fploc_eval_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto a = (dir / "a.tum").string(), b = (dir / "b.tum").string();
  const auto t = loop(20);
  write_tum(a, t);
  write_tum(b, read_tum(a));
  std::ifstream fa(a), fb(b);
  const std::string sa((std::istreambuf_iterator<char>(fa)), {}), sb((std::istreambuf_iterator<char>(fb)), {});
  EXPECT_EQ(sa, sb);
  EXPECT_EQ(read_tum(a).size(), 20u);
  {
    std::ofstream bad(b);
    bad << "# comment\n1 2 3\n";
  }
  try {
    read_tum(b);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("b.tum:2:"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(Plot, SvgHasBothPaths) {
  const auto gt = loop(30);
  const auto svg = plot_svg(gt, gt, "a < b");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  size_t n = 0;
  for (size_t p = svg.find("<polyline"); p != std::string::npos; p = svg.find("<polyline", p + 1)) ++n;
  EXPECT_EQ(n, 2u);
  EXPECT_NE(svg.find("a &lt; b"), std::string::npos);
}

// The plot a reader wants (issue 14): the plan under the trajectories, axes in metres, a legend and the
// estimate coloured by its error with a colour bar.
TEST(Plot, PlanAxesLegendAndErrorColours) {
  const auto gt = loop(30);
  auto est = gt;
  for (size_t i = 0; i < est.size(); ++i) est[i].p.x() += 0.01 * double(i);
  PlotOptions o;
  o.plan = {{Eigen::Vector2d(-20, -20), Eigen::Vector2d(20, -20), Eigen::Vector2d(20, 20)}};
  const auto pairs = associate(gt, est);
  o.est_error = pose_errors(gt, est, pairs);
  ASSERT_EQ(o.est_error.size(), est.size());
  EXPECT_NEAR(o.est_error.back(), 0.01 * double(est.size() - 1), 1e-9);
  const auto svg = plot_svg(gt, est, "t", Eigen::Isometry3d::Identity(), o);
  EXPECT_NE(svg.find("x [m]"), std::string::npos);
  EXPECT_NE(svg.find("y [m]"), std::string::npos);
  EXPECT_NE(svg.find("floor plan"), std::string::npos);
  EXPECT_NE(svg.find("estimate (colour: error)"), std::string::npos);
  EXPECT_NE(svg.find("ground truth"), std::string::npos);
  // Tick labels: the plan's corner at -20 / 20 m is inside the axes.
  EXPECT_NE(svg.find(">-20</text>"), std::string::npos);
  EXPECT_NE(svg.find(">20</text>"), std::string::npos);
  // One coloured segment per consecutive estimate pair: the first (lowest error) blue, the last red (jet).
  const size_t g0 = svg.find("<title>estimate (colour: error)</title>");
  ASSERT_NE(g0, std::string::npos);
  const size_t g1 = svg.find("</g>", g0);
  size_t n = 0;
  for (size_t p = svg.find("<line x1", g0); p < g1; p = svg.find("<line x1", p + 1)) ++n;
  EXPECT_EQ(n, est.size() - 1);
  const std::string first = svg.substr(svg.find("stroke=\"#", g0) + 8, 7), last = svg.substr(svg.rfind("stroke=\"#", g1) + 8, 7);
  EXPECT_EQ(first, "#000080");  // jet(0)
  EXPECT_EQ(last.substr(3), "0000") << last;  // jet(~1): red only
  EXPECT_GT(std::stoi(last.substr(1, 2), nullptr, 16), 0x80) << last;
}

// A narrow plan (a corridor 0.2 m wide, 20 m long: the plot area is a few px wide) still shows its whole legend:
// the picture is as wide as the legend's text; sub-centimetre errors on the colour bar are in mm, not "6.65e-05 m".
TEST(Plot, NarrowPlanKeepsTheLegendAndSmallErrorsReadInMm) {
  Trajectory gt, est;
  for (int i = 0; i < 50; ++i) {
    StampedPose p;
    p.t = i;
    p.p = Eigen::Vector3d(0.1, 0.4 * i, 0);
    gt.push_back(p);
    p.p.x() += 6.65e-5 * (1 + i % 2);
    est.push_back(p);
  }
  PlotOptions o;
  o.plan = {{Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 20)}, {Eigen::Vector2d(0.2, 0), Eigen::Vector2d(0.2, 20)}};
  o.plan_label = "floor plan: floor 'a long floor name'";
  o.est_error = pose_errors(gt, est, associate(gt, est));
  const auto svg = plot_svg(gt, est, "t", Eigen::Isometry3d::Identity(), o);
  const double width = std::stod(svg.substr(svg.find("width=\"") + 7));
  // The legend's last text (the grid step) starts at x and runs ~7.5 px a character.
  const size_t g = svg.find(">grid ");
  ASSERT_NE(g, std::string::npos);
  const size_t xa = svg.rfind("x=\"", g) + 3;
  const double x = std::stod(svg.substr(xa));
  const size_t len = svg.find("</text>", g) - g - 1;
  EXPECT_GE(width, x + 7.5 * double(len)) << "legend cut off: width " << width << ", grid text at " << x;
  EXPECT_NE(svg.find("floor plan: floor 'a long floor name'"), std::string::npos);
  EXPECT_NE(svg.find(">0.133 mm</text>"), std::string::npos) << svg.substr(svg.find("error</text>") - 200, 220);
  EXPECT_NE(svg.find(">0.0665 mm</text>"), std::string::npos);
  EXPECT_EQ(svg.find("e-05"), std::string::npos);
}

// A map with a stray speck far from the building: by default the axes take it in (the building shrinks to a
// corner of the plot); framed on the trajectories they keep to the path and its margin, and the plan is clipped.
TEST(Plot, FramedOnTheTrajectoriesAFarSpeckIsLeftOut) {
  const auto gt = loop(30);
  PlotOptions o;
  o.plan = {{Eigen::Vector2d(-3, -3), Eigen::Vector2d(3, -3)}, {Eigen::Vector2d(500, 500), Eigen::Vector2d(500.1, 500)}};
  const auto all = plot_svg(gt, gt, "t", Eigen::Isometry3d::Identity(), o);
  EXPECT_NE(all.find(">500</text>"), std::string::npos);
  o.frame_trajectories = true;
  const auto framed = plot_svg(gt, gt, "t", Eigen::Isometry3d::Identity(), o);
  EXPECT_EQ(framed.find(">500</text>"), std::string::npos);
  EXPECT_EQ(framed.find(">100</text>"), std::string::npos);
  EXPECT_NE(framed.find("clip-path=\"url(#axes)\""), std::string::npos);
}
