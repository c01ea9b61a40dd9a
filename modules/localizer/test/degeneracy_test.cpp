// The published covariance and status (degeneracy.h): growth along an open direction, POOR naming it,
// back to OK when the plan fixes the pose again; the matrix helpers.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fploc/localizer/degeneracy.h"
#include "fploc/localizer/localizer.h"
#include "fploc/localizer/rival.h"
#include "fploc/matcher/map.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::matcher;
using namespace fploc::localizer;

namespace {
Eigen::Matrix3d diag(double sx, double sy, double syaw) { return Eigen::Vector3d(sx * sx, sy * sy, syaw * syaw).asDiagonal(); }
// A tracker's scene for the dead reckoning's rules: fixes with a 1 cm covariance, the matcher's twist 0.5 m/s along x,
// the truth from (1, 2) and the dead-reckoned pose on it with a 5 cm / 0.57 deg covariance.
// A corridor along x between walls at y = 0 and 2, with a fin every 1.5 m on the upper wall (beyond the sensor's 6 m
// range the view repeats), without the fin at `missing_x` when given.
FloorPlan fins_corridor(double missing_x = NAN) {
  FloorPlan plan;
  plan.elements.push_back(Element::segment({-20, 0}, {200, 0}));
  plan.elements.push_back(Element::segment({-20, 2}, {200, 2}));
  for (double x = -20; x < 200; x += 1.5)
    if (!(std::abs(x - missing_x) < 0.1)) plan.elements.push_back(Element::segment({x, 2}, {x, 1.6}));
  return plan;
}
// The sensor of the corridor tests: 6 m range, 5 mm range noise.
fploc::testing::SynthOptions six_metre_sensor() {
  fploc::testing::SynthOptions so;
  so.noise_sigma = 0.005;
  so.max_range = 6;
  return so;
}
struct DeadReckoningScene {
  Eigen::Matrix3d fixed = diag(0.01, 0.01, 0.002);
  matcher::Twist2 v{0.5, 0, 0};
  int64_t t = 0;
  Pose2 truth{1.0, 2.0, 0.0};
  DeadReckoned dr;
  DeadReckoningScene() { dr.covariance = diag(0.05, 0.05, 0.01); }
};
}  // namespace

TEST(Degeneracy, TighterOfTakesEachDirectionFromTheBetterSource) {
  const Eigen::Matrix3d A = diag(0.01, 1.0, 0.01), B = diag(1.0, 0.02, 0.1);
  const Eigen::Matrix3d T = tighter_of(A, B);
  EXPECT_NEAR(T(0, 0), 1e-4, 1e-9);
  EXPECT_NEAR(T(1, 1), 4e-4, 1e-9);
  EXPECT_NEAR(T(2, 2), 1e-4, 1e-9);
  // Never tighter than both, never looser than either.
  const Eigen::Matrix3d S = tighter_of(B, B);
  EXPECT_TRUE(S.isApprox(B, 1e-9));
}

TEST(Degeneracy, StartsFromTheInitialPoseUncertaintyWithAnUnknownVelocity) {
  UncertaintyTracker tr;
  tr.reset(0.05, 0.02);
  const Eigen::Matrix3d open = diag(100.0, 0.005, 0.002);
  auto s = tr.update(0, open, true, FitStatus::kOk);
  EXPECT_NEAR(std::sqrt(s.covariance(0, 0)), 0.05, 1e-9);  // the initial pose's along the open x
  EXPECT_EQ(s.status, FitStatus::kOk);
  // The velocity along x is unknown (the platform's speed): one frame later the pose is too.
  s = tr.update(100000, open, true, FitStatus::kOk);
  EXPECT_NEAR(std::sqrt(s.covariance(0, 0)), 0.05 + 1.5 * 0.1, 1e-6);
  EXPECT_EQ(s.status, FitStatus::kPoor);
  EXPECT_NE(s.text.find("along 0 deg"), std::string::npos) << s.text;
}

TEST(Degeneracy, GrowLinearAddsToTheStandardDeviation) {
  const Eigen::Matrix3d G = grow_linear(diag(0.03, 0.04, 0.01), Eigen::Vector3d(0.01, 0.01, 0.001));
  EXPECT_NEAR(std::sqrt(G(0, 0)), 0.04, 1e-9);
  EXPECT_NEAR(std::sqrt(G(1, 1)), 0.05, 1e-9);
  EXPECT_NEAR(std::sqrt(G(2, 2)), 0.011, 1e-9);
}

TEST(Degeneracy, CorridorGrowsPoorNamesTheDirectionThenRecovers) {
  UncertaintyConfig cfg;
  cfg.velocity_sigma_mps = 0.05;
  cfg.accel_sigma_mps2 = 0.5;
  cfg.max_velocity_error_mps = 1.5;
  cfg.poor_sigma_m = 0.1;
  cfg.confirm_fixes = 0;  // (the start is a re-acquisition: ReacquiredTrackIsPoorUntilFixesAgree)
  UncertaintyTracker tr(cfg);
  const int64_t dt = 100000;  // 10 Hz
  int64_t t = 0;
  const Eigen::Matrix3d fixed = diag(0.005, 0.005, 0.002);
  // A 30-degree corridor: the frames fix the pose across it only.
  const double a = 30 * M_PI / 180;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  R.topLeftCorner<2, 2>() << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  const Eigen::Matrix3d open = R * diag(100.0, 0.005, 0.002) * R.transpose();
  for (int k = 0; k < 10; ++k, t += dt) {
    const auto s = tr.update(t, fixed, true, FitStatus::kOk);
    EXPECT_EQ(s.status, FitStatus::kOk);
    EXPECT_NEAR(s.sigma_max_m, 0.005, 1e-6);
  }
  double sigma = 0.005, sigma_v = 0.05;
  int first_poor = -1;
  for (int k = 0; k < 30; ++k, t += dt) {
    const auto s = tr.update(t, open, true, FitStatus::kOk);
    // Along the corridor the velocity error grows by accel * dt per frame (up to the platform's speed)
    // and the position's standard deviation by that velocity error * dt; across the corridor it stays.
    sigma_v = std::min(1.5, sigma_v + 0.5 * 0.1);
    sigma += sigma_v * 0.1;
    EXPECT_NEAR(s.sigma_max_m, sigma, 1e-6) << k;
    EXPECT_NEAR(std::abs(s.weak_direction_rad), a, 1e-3);
    const Eigen::Vector2d across(-std::sin(a), std::cos(a));
    EXPECT_NEAR(std::sqrt(across.dot(s.covariance.topLeftCorner<2, 2>() * across)), 0.005, 1e-4);
    EXPECT_TRUE(s.frame_degenerate);
    if (s.status == FitStatus::kPoor && first_poor < 0) {
      first_poor = k;
      EXPECT_NE(s.text.find("along 30 deg"), std::string::npos) << s.text;
    }
  }
  EXPECT_EQ(first_poor, 4);  // 0.005 + 0.01 + 0.015 + 0.02 + 0.025 + 0.03 > 0.1
  // The plan fixes the pose again: OK with the frame's covariance at once.
  const auto s = tr.update(t, fixed, true, FitStatus::kOk);
  EXPECT_EQ(s.status, FitStatus::kOk);
  EXPECT_TRUE(s.text.empty());
  EXPECT_NEAR(s.sigma_max_m, 0.005, 1e-6);
}

TEST(Degeneracy, MatcherStatusIsKept) {
  UncertaintyTracker tr;
  const Eigen::Matrix3d fixed = diag(0.005, 0.005, 0.002);
  tr.update(0, fixed, true, FitStatus::kOk);
  // A frame the matcher did not accept adds nothing: the prediction grows.
  const auto p = tr.update(100000, fixed, true, FitStatus::kPoor, "inliers 3/100");
  EXPECT_EQ(p.status, FitStatus::kPoor);
  EXPECT_EQ(p.text, "inliers 3/100");
  EXPECT_NEAR(p.sigma_max_m, 0.005 + (0.05 + 0.5 * 0.1) * 0.1, 1e-6);  // grown by the velocity error over one frame
  const auto l = tr.update(200000, fixed, true, FitStatus::kLost, "lost");
  EXPECT_EQ(l.status, FitStatus::kLost);
  EXPECT_GT(l.sigma_max_m, 10.0);
}

// The whole localizer along a corridor whose ends are never seen, driven at 0.5 m/s: the plan fixes y and
// the heading, nothing fixes x. The published status must say POOR before the x error grows, and never OK
// while the pose is more than 0.3 m off (false OK); across the corridor the covariance stays small.
TEST(Degeneracy, LocalizerAlongAnEndlessCorridorIsPoorBeforeTheErrorGrows) {
  const FloorPlan plan = fploc::testing::endless_corridor();
  auto map = make_localization_map(plan, "brute-force");
  localizer::Localizer loc(*map.lookup, {});
  loc.set_pose({50, 1, 0}, 0.15);
  fploc::testing::SynthOptions so;
  so.max_range = 8;
  so.noise_sigma = 0.005;
  std::vector<localizer::Pose> finals;
  int first_poor = -1, false_ok = 0;
  double err_at_first_poor = -1, max_err = 0;
  for (int k = 0; k < 60; ++k) {
    const int64_t utime = k * 100'000;
    const Pose2 truth{50 + 0.05 * k, 1, 0};
    so.seed = uint32_t(k + 1);
    const auto s = loc.process(fploc::testing::synth_frame(plan, truth, so, utime), &finals);
    ASSERT_TRUE(s.latest);
    const double err = std::hypot(s.latest->pose.x - truth.x, s.latest->pose.y - truth.y);
    max_err = std::max(max_err, err);
    if (s.latest->status == FitStatus::kOk && err > 0.3) ++false_ok;
    if (s.latest->status == FitStatus::kPoor && first_poor < 0) {
      first_poor = k;
      err_at_first_poor = err;
      EXPECT_NE(s.latest->status_text.find("along 0 deg"), std::string::npos) << s.latest->status_text;
    }
    EXPECT_NE(s.latest->status, FitStatus::kLost) << k;
    EXPECT_LT(std::sqrt(s.latest->covariance(1, 1)), 0.02) << k;  // across: the walls
  }
  std::printf("endless corridor: first POOR at frame %d (error %.3f m), max error %.2f m\n", first_poor, err_at_first_poor,
              max_err);
  ASSERT_GE(first_poor, 0);
  EXPECT_LT(err_at_first_poor, 0.1);
  EXPECT_EQ(false_ok, 0);
}

TEST(Degeneracy, ChiSquareQuantileOfThreeSigmas) {
  EXPECT_NEAR(chi2_3dof_of_sigmas(3.0), 14.16, 0.01);
  EXPECT_NEAR(chi2_3dof_of_sigmas(1.0), 3.53, 0.01);
}

// The innovation gate: a confident fix far from where the last fix and the matcher's twist say the
// platform is now is refused (POOR, naming it), the next consistent one is taken again.
TEST(Degeneracy, RefusesAConfidentFixFarFromThePrediction) {
  UncertaintyTracker tr;
  const Eigen::Matrix3d fixed = diag(0.01, 0.01, 0.002);
  matcher::Twist2 v;
  v.vx = 0.5;  // body forward; heading 0: +x in the plan
  int64_t t = 0;
  Pose2 p{1.0, 2.0, 0.0};
  for (int k = 0; k < 20; ++k, t += 100000, p.x += 0.05) {
    const auto s = tr.update(t, fixed, true, FitStatus::kOk, {}, &p, &v);
    // (no initial pose: the first fixes are a re-acquisition, confirmed by the fifth)
    ASSERT_EQ(s.status, k < 4 ? FitStatus::kPoor : FitStatus::kOk) << k << " " << s.text;
    EXPECT_LT(s.innovation_sigma, 1.0);
  }
  // 0.3 m sideways in one frame, with a 1 cm fix.
  Pose2 jump = p;
  jump.y += 0.3;
  auto s = tr.update(t, fixed, true, FitStatus::kOk, {}, &jump, &v);
  EXPECT_EQ(s.status, FitStatus::kPoor);
  EXPECT_TRUE(s.refused);
  EXPECT_NE(s.text.find("fix refused"), std::string::npos) << s.text;
  EXPECT_GT(s.innovation_sigma, 10.0);
  // The prediction went on: the next fix where the platform really is passes again.
  t += 100000;
  p.x += 0.05;
  Pose2 next = p;
  next.x += 0.05;
  s = tr.update(t, fixed, true, FitStatus::kOk, {}, &next, &v);
  EXPECT_EQ(s.status, FitStatus::kOk) << s.text;
  EXPECT_FALSE(s.refused);
}

TEST(Degeneracy, GateOffOrWithoutAFixChangesNothing) {
  UncertaintyConfig off, on;
  off.gate_sigma = 0;
  off.confirm_fixes = on.confirm_fixes = 0;  // (the gate alone)
  UncertaintyTracker a(off), b(on);
  const Eigen::Matrix3d fixed = diag(0.01, 0.01, 0.002);
  Pose2 p{0, 0, 0};
  a.update(0, fixed, true, FitStatus::kOk, {}, &p);
  b.update(0, fixed, true, FitStatus::kOk);
  Pose2 jump{1.0, 0, 0};
  EXPECT_EQ(a.update(100000, fixed, true, FitStatus::kOk, {}, &jump).status, FitStatus::kOk);
  EXPECT_EQ(b.update(100000, fixed, true, FitStatus::kOk).status, FitStatus::kOk);
}

// Re-acquisition: a fix taken where the position was unknown (after LOST) is POOR until confirm_fixes accepted
// fixes agree in a row; a POOR frame starts the count again; with confirm_fixes 0 a single fix is OK. A
// corridor (fixed across) is not a re-acquisition: CorridorGrowsPoorNamesTheDirectionThenRecovers.
TEST(Degeneracy, ReacquiredTrackIsPoorUntilFixesAgree) {
  UncertaintyConfig cfg, off;
  off.confirm_fixes = 0;
  ASSERT_EQ(cfg.confirm_fixes, 5);
  UncertaintyTracker tr(cfg), single(off);
  const Eigen::Matrix3d fixed = diag(0.01, 0.01, 0.002);
  matcher::Twist2 v;
  v.vx = 0.5;
  int64_t t = 0;
  Pose2 p{1.0, 2.0, 0.0};
  auto step = [&](UncertaintyTracker& u, FitStatus st) { return u.update(t, fixed, true, st, {}, &p, &v); };
  for (int k = 0; k < 10; ++k, t += 100000, p.x += 0.05) {
    step(tr, FitStatus::kOk);
    step(single, FitStatus::kOk);
  }
  ASSERT_EQ(step(tr, FitStatus::kOk).status, FitStatus::kOk);
  // LOST, then a fix 3 m away (a parallel corridor): the gate cannot refuse it (the position is unknown).
  step(tr, FitStatus::kLost);
  step(single, FitStatus::kLost);
  t += 100000;
  p.y += 3.0;
  std::vector<FitStatus> seen;
  for (int k = 0; k < 7; ++k, t += 100000, p.x += 0.05) {
    if (k == 2) {  // one POOR frame: the count starts again
      const auto s = step(tr, FitStatus::kPoor);
      EXPECT_EQ(s.status, FitStatus::kPoor);
      step(single, FitStatus::kPoor);
      continue;
    }
    const auto s = step(tr, FitStatus::kOk);
    seen.push_back(s.status);
    if (s.status == FitStatus::kPoor) { EXPECT_NE(s.text.find("re-acquired"), std::string::npos) << s.text; }
    const auto s1 = step(single, FitStatus::kOk);
    EXPECT_EQ(s1.status, FitStatus::kOk) << k << " " << s1.text;  // off: every fix OK
  }
  // Fixes 1, 2 | POOR | 1, 2, 3, 4: still POOR; the fifth in a row is OK.
  ASSERT_EQ(seen.size(), 6u);
  for (size_t k = 0; k < seen.size(); ++k) EXPECT_EQ(seen[k], FitStatus::kPoor) << k;
  EXPECT_EQ(step(tr, FitStatus::kOk).status, FitStatus::kOk);
}

// A weak fix (under weak_fit_ratio of its points on the plan) is published POOR, naming its share; the covariance
// and the track are as for any fix (the next strong one is OK at once); weak_fit_ratio 0: OK.
TEST(Degeneracy, WeakFitIsPublishedPoor) {
  UncertaintyConfig cfg, off;
  cfg.confirm_fixes = off.confirm_fixes = 0;
  off.weak_fit_ratio = 0;
  ASSERT_EQ(cfg.weak_fit_ratio, 0.5);
  UncertaintyTracker tr(cfg), keep(off);
  const Eigen::Matrix3d fixed = diag(0.01, 0.01, 0.002);
  Pose2 p{0, 0, 0};
  matcher::Twist2 v;
  int64_t t = 0;
  for (double ratio : {0.9, 0.46, 0.5, 0.9}) {
    const auto s = tr.update(t, fixed, true, FitStatus::kOk, {}, &p, &v, ratio);
    EXPECT_EQ(s.status, ratio < 0.5 ? FitStatus::kPoor : FitStatus::kOk) << ratio;
    if (ratio < 0.5) { EXPECT_NE(s.text.find("weak fit: 46 %"), std::string::npos) << s.text; }
    EXPECT_NEAR(s.sigma_max_m, 0.01, 1e-6);
    EXPECT_EQ(keep.update(t, fixed, true, FitStatus::kOk, {}, &p, &v, ratio).status, FitStatus::kOk);
    t += 100000;
  }
}

// A fix whose points land where the map says it is empty (more than a quarter of those the map knows about) is
// published POOR with the share; at or below a quarter, or with the check off, it stays OK.
TEST(Degeneracy, FixContradictingTheMapsFreeSpaceIsPublishedPoor) {
  UncertaintyConfig cfg, off;
  cfg.confirm_fixes = off.confirm_fixes = 0;
  off.max_contradicted = 0;
  ASSERT_EQ(cfg.max_contradicted, 0.25);
  UncertaintyTracker tr(cfg), keep(off);
  const Eigen::Matrix3d fixed = diag(0.01, 0.01, 0.002);
  Pose2 p{0, 0, 0};
  matcher::Twist2 v;
  int64_t t = 0;
  for (double c : {0.0, 0.3, 0.25, 0.1, 0.6}) {
    const auto s = tr.update(t, fixed, true, FitStatus::kOk, {}, &p, &v, 0.9, nullptr, c);
    EXPECT_EQ(s.status, c > 0.25 ? FitStatus::kPoor : FitStatus::kOk) << c;
    if (c == 0.3) { EXPECT_NE(s.text.find("the map says empty where 30 %"), std::string::npos) << s.text; }
    EXPECT_EQ(keep.update(t, fixed, true, FitStatus::kOk, {}, &p, &v, 0.9, nullptr, c).status, FitStatus::kOk);
    t += 100000;
  }
}

// With odometry (2D laser logs: frames a metre and tens of degrees apart, seconds between them), the tracked
// prediction is the last fix composed with the odometry's increment: fixes that follow a 1 m / 30 degree step
// 2 s apart are taken (OK, not a re-acquisition after the first confirmation), where the twist's constant
// velocity would refuse every one of them; a fix 2 m beside where the odometry says (its 1-sigma over the step
// is 0.35 m) is still refused.
TEST(Degeneracy, OdometryPredictsTheTrackBetweenDistantFrames) {
  const Eigen::Matrix3d fixed = diag(0.0004, 0.0004, 0.0001);  // 2 cm, 0.6 deg
  const Pose2 step{1.0, 0.0, 30 * M_PI / 180};
  for (bool with_odometry : {true, false}) {  // (the control: the same fixes without it)
    UncertaintyTracker tr;
    tr.reset(0.05, 0.02);
    matcher::Twist2 still;
    Pose2 p{1.0, 2.0, 0.0};
    int refused = 0, ok = 0;
    for (int k = 0; k < 12; ++k) {
      const auto s = tr.update(int64_t(k) * 2'000'000, fixed, true, FitStatus::kOk, {}, &p, &still, 1.0,
                               with_odometry && k > 0 ? &step : nullptr);
      refused += s.refused;
      ok += s.status == FitStatus::kOk;
      p = compose(p, step);
    }
    if (with_odometry) {
      EXPECT_EQ(refused, 0);
      EXPECT_EQ(ok, 12);
    } else {
      EXPECT_GE(refused, 10);
    }
  }
  UncertaintyTracker tr;
  tr.reset(0.05, 0.02);
  Pose2 p{1.0, 2.0, 0.0};
  tr.update(0, fixed, true, FitStatus::kOk, {}, &p, nullptr, 1.0, nullptr);
  Pose2 beside = compose(p, step);
  beside.y += 2.0;
  const auto s = tr.update(2'000'000, fixed, true, FitStatus::kOk, {}, &beside, nullptr, 1.0, &step);
  EXPECT_TRUE(s.refused) << s.text;
  EXPECT_EQ(s.status, FitStatus::kPoor);
}

// After a stretch not published OK, a fix beyond the gate of the dead-reckoned pose (the last OK pose carried on by
// the LiDAR odometry) is published POOR, with the offset in its covariance, until a fix agrees with it; without a
// dead-reckoned pose, or with the gate off, the tracker is as before.
TEST(Degeneracy, FixFarFromTheDeadReckonedPoseIsPoorUntilOneAgrees) {
  UncertaintyConfig cfg, off;
  cfg.confirm_fixes = off.confirm_fixes = 0;  // (the re-acquisition's own confirmation: ReacquiredTrackIsPoorUntilFixesAgree)
  off.dead_reckoning_gate_sigma = 0;
  UncertaintyTracker tr(cfg), gate_off(off), no_dr(cfg);
  DeadReckoningScene sc;
  auto& [fixed, v, t, truth, dr] = sc;
  auto step = [&](UncertaintyTracker& u, FitStatus st, const Pose2& fix, bool with_dr) {
    dr.pose = truth;
    return u.update(t, fixed, true, st, {}, &fix, &v, 1.0, nullptr, 0.0, with_dr ? &dr : nullptr);
  };
  auto all = [&](FitStatus st, const Pose2& fix) {
    const auto s = step(tr, st, fix, true);
    EXPECT_EQ(step(gate_off, st, fix, true).status, st == FitStatus::kOk ? FitStatus::kOk : st);
    EXPECT_EQ(step(no_dr, st, fix, false).status, st == FitStatus::kOk ? FitStatus::kOk : st);
    t += 100000;
    truth.x += 0.05;
    return s;
  };
  for (int k = 0; k < 10; ++k) {
    const auto s = all(FitStatus::kOk, truth);
    EXPECT_EQ(s.status, FitStatus::kOk);
    EXPECT_FALSE(tr.wants_dead_reckoning());  // tracking: nothing to check
    EXPECT_EQ(s.dead_reckoned_sigma, 0);
  }
  for (int k = 0; k < 6; ++k) all(k < 5 ? FitStatus::kPoor : FitStatus::kLost, truth);
  EXPECT_TRUE(tr.wants_dead_reckoning());
  // Re-acquired 0.5 m sideways (shelf faces on the walls behind them): POOR, the offset in the covariance.
  for (int k = 0; k < 8; ++k) {
    const auto s = all(FitStatus::kOk, Pose2{truth.x, truth.y + 0.5, truth.yaw});
    EXPECT_EQ(s.status, FitStatus::kPoor) << k;
    EXPECT_TRUE(s.off_dead_reckoning);
    EXPECT_NE(s.text.find("from the dead-reckoned pose"), std::string::npos) << s.text;
    EXPECT_GT(std::sqrt(s.covariance(1, 1)), 0.45);
    EXPECT_TRUE(tr.wants_dead_reckoning());
  }
  // Lost again, and re-acquired where the odometry says: OK, and nothing more to check.
  for (int k = 0; k < 6; ++k) all(k < 5 ? FitStatus::kPoor : FitStatus::kLost, truth);
  const auto s = all(FitStatus::kOk, Pose2{truth.x + 0.03, truth.y - 0.02, truth.yaw});
  EXPECT_EQ(s.status, FitStatus::kOk) << s.text;
  EXPECT_GT(s.dead_reckoned_sigma, 0);
  EXPECT_FALSE(tr.wants_dead_reckoning());
  // (the next jump is the innovation gate's, as before)
  EXPECT_NE(step(tr, FitStatus::kOk, Pose2{truth.x, truth.y + 0.5, truth.yaw}, true).text.find("fix refused"), std::string::npos);
}

// A stretch that refused a fix against the dead reckoning (the track slid 0.5 m sideways) ends only when fixes agree
// within dr_confirm_gate_sigma (2): the track drifting back, a fix 0.16 m off (Mahalanobis ~3.1, inside the 3-sigma gate
// that refused the ones before it) is still published POOR ("... within 2 sigma ..."), and OK only once fixes lie
// within 2 sigma. (The corridor's mixed world, seed 2: such fixes at the gate's edge ended the stretch and 24 poses
// 0.39-0.42 m off were published OK.) With dr_confirm_gate_sigma at 3 the 0.16 m fix is OK again, as before.
TEST(Degeneracy, AStretchWithARefusedFixEndsOnlyWithinTheTighterGate) {
  for (double confirm_gate : {2.0, 3.0}) {
    UncertaintyConfig cfg;
    cfg.confirm_fixes = 0;  // (the re-acquisition's own confirmation is another rule)
    cfg.dr_confirm_gate_sigma = confirm_gate;
    UncertaintyTracker tr(cfg);
    DeadReckoningScene sc;
    auto& [fixed, v, t, truth, dr] = sc;
    auto step = [&](double off_y) {
      dr.pose = truth;
      const Pose2 fix{truth.x, truth.y + off_y, truth.yaw};
      const auto s = tr.update(t, fixed, true, FitStatus::kOk, {}, &fix, &v, 1.0, nullptr, 0.0, &dr);
      t += 100000;
      truth.x += 0.05;
      return s;
    };
    for (int k = 0; k < 10; ++k) EXPECT_EQ(step(0).status, FitStatus::kOk);
    // Slides sideways 2 cm per frame to 0.5 m (within the tracker's own innovation gate each frame).
    int refused = 0;
    for (int k = 1; k <= 25; ++k) refused += step(0.02 * k).off_dead_reckoning;
    EXPECT_GT(refused, 10);
    // Back to 0.16 m, held there.
    for (double y = 0.48; y > 0.165; y -= 0.02) step(y);
    int ok_at_edge = 0, said = 0;
    for (int k = 0; k < 5; ++k) {
      const auto s = step(0.16);
      EXPECT_FALSE(s.off_dead_reckoning) << s.text;  // inside the 3-sigma gate
      EXPECT_GT(s.dead_reckoned_sigma, 2.83);          // outside the 2-sigma one
      ok_at_edge += s.status == FitStatus::kOk;
      said += s.text.find("within 2 sigma of the dead-reckoned pose") != std::string::npos;
    }
    // Back onto the dead-reckoned pose: OK, the stretch over.
    for (double y = 0.14; y > 0.005; y -= 0.02) step(y);
    const auto s = step(0.0);
    EXPECT_EQ(s.status, FitStatus::kOk) << s.text;
    EXPECT_FALSE(tr.wants_dead_reckoning());
    std::printf("confirm gate %.0f sigma: %d fixes refused, %d of 5 at 0.16 m published OK\n", confirm_gate, refused, ok_at_edge);
    if (confirm_gate == 2.0) {
      EXPECT_EQ(ok_at_edge, 0);
      EXPECT_EQ(said, 5);
    } else {
      EXPECT_EQ(ok_at_edge, 5);
    }
  }
}

// The Localizer end to end: the track goes POOR where cabinets stand 0.35 m in front of both walls (the world, not the
// plan), and a relocalizer then re-seeds it one period off along a corridor whose wall has a fin every 1.5 m (beyond
// the sensor's 6 m range the view repeats), where every fix registers as well as the truth, fixed in every direction.
// The Localizer carries the last OK pose through the stretch with the LiDAR odometry of its frames: the fixes on the
// twin are published POOR, 1.5 m from the dead-reckoned pose. (Here the window also holds the true track: it carries
// its correction over the re-seed. After a LOST longer than the window's max_keyframe_gap_s it restarts from the fix,
// and the corridor worlds' re-acquisitions were published OK metres off: FixFarFromTheDeadReckonedPose... above.)
TEST(Degeneracy, LocalizerReseededOnePeriodOffIsPoorAgainstTheDeadReckoning) {
  const FloorPlan plan = fins_corridor();
  FloorPlan world = plan;
  world.elements.push_back(Element::segment({3, 0.35}, {6.5, 0.35}));
  world.elements.push_back(Element::segment({3, 1.65}, {6.5, 1.65}));
  auto map = make_localization_map(plan, "brute-force");
  for (bool gate_on : {true, false}) {
    localizer::Config cfg;
    cfg.uncertainty.rival_ratio = 0;  // (the second fit one period on: ReacquisitionWithASecondFitAsGoodStaysPoor)
    if (!gate_on) cfg.uncertainty.dead_reckoning_gate_sigma = 0;
    localizer::Localizer loc(*map.lookup, cfg);
    loc.set_pose({0.2, 0.8, 0}, 0.15);
    fploc::testing::SynthOptions so = six_metre_sensor();
    std::vector<localizer::Pose> finals;
    int ok_before = 0, false_ok = 0, on_twin = 0, said = 0;
    bool reseeded = false;
    for (int k = 0; k < 110; ++k) {
      const int64_t utime = k * 100'000;
      const Pose2 truth{0.2 + 0.1 * k, 0.8, 0};
      so.seed = uint32_t(k + 1);
      const FeatureFrame f = fploc::testing::synth_frame(world, truth, so, utime);
      if (!reseeded && truth.x > 7.5) {  // out of the cabinets: the relocalizer's answer, one period off
        loc.set_pose({truth.x + 1.5, truth.y, truth.yaw}, 0.1);
        reseeded = true;
      }
      const auto s = loc.process(f, &finals);
      ASSERT_TRUE(s.latest);
      const double err = std::hypot(s.latest->pose.x - truth.x, s.latest->pose.y - truth.y);
      if (truth.x < 2.5 && s.latest->status == FitStatus::kOk) ++ok_before;
      if (reseeded && s.sfr.match.status == FitStatus::kOk && std::abs(s.sfr.match.pose.x - truth.x - 1.5) < 0.1) ++on_twin;
      if (s.latest->status == FitStatus::kOk && err > 0.3) ++false_ok;
      if (s.latest->status_text.find("from the dead-reckoned pose") != std::string::npos) ++said;
    }
    std::printf("re-seeded one period off, dead-reckoning gate %s: %d OK before, %d fixes on the twin, %d false OK, "
                "%d said\n", gate_on ? "on" : "off", ok_before, on_twin, false_ok, said);
    // (of 23 frames: the dead reckoning starts without a velocity, its pose lags the first fixes by 0.1 m and refuses two
    // of them; the stretch that starts ends with five fixes within dr_confirm_gate_sigma: AStretchWithARefusedFix...)
    EXPECT_GT(ok_before, 12);
    EXPECT_GT(on_twin, 20);  // the scenario: the matcher stays on the twin
    EXPECT_EQ(false_ok, 0);
    if (gate_on) EXPECT_GT(said, 20);
    else EXPECT_EQ(said, 0);
  }
}

// A track re-seeded one period off along the fins' corridor (as above, without the cabinets), whose fins lack one
// (x = 13) in the plan and the world: from the twin, the fin before the gap lands on it, so the truth 1.5 m back explains
// more points than the twin's fixes. The twin's fixes are refused against the dead reckoning; then one frame the
// odometry cannot register (nothing within range) starts it again at a fix in doubt, inside that stretch, and no
// dead-reckoned pose is left to check the stretch's end against. It must not end at the next OK fix (before: the
// twin's fixes published OK 1.5 m off from there on): a second-fit search finds the truth explaining more points than
// the fix, which makes it a re-acquisition: POOR, saying so. Without the lost frame the dead reckoning says so itself.
TEST(Degeneracy, DeadReckoningLostInAStretchMakesItsEndAReacquisition) {
  const FloorPlan plan = fins_corridor(13.0);
  auto map = make_localization_map(plan, "brute-force");
  for (bool lose_it : {true, false}) {
    localizer::Config cfg;
    cfg.uncertainty.rival_search_m = 1.5;  // (the truth one period back)
    localizer::Localizer loc(*map.lookup, cfg);
    loc.set_pose({0.2, 0.8, 0}, 0.15);
    fploc::testing::SynthOptions so = six_metre_sensor();
    std::vector<localizer::Pose> finals;
    int on_twin = 0, ok_on_twin = 0, said = 0;
    for (int k = 0; k < 110; ++k) {
      const Pose2 truth{0.2 + 0.1 * k, 0.8, 0};
      fploc::testing::SynthOptions sk = so;
      sk.seed = uint32_t(k + 1);
      if (k == 60) loc.set_pose({truth.x + 1.5, truth.y, truth.yaw}, 0.1);  // the relocalizer's answer, one period on
      if (k == 70 && lose_it) sk.max_range = 0.5;                           // nothing in range
      const auto s = loc.process(fploc::testing::synth_frame(plan, truth, sk, k * 100'000), &finals);
      ASSERT_TRUE(s.latest);
      if (k <= 70 || s.sfr.match.status != FitStatus::kOk || std::abs(s.sfr.match.pose.x - truth.x - 1.5) > 0.1) continue;
      ++on_twin;
      ok_on_twin += loc.uncertainty().status == FitStatus::kOk;
      said += loc.uncertainty().text.find(lose_it ? "a second fit" : "dead-reckoned pose") != std::string::npos;
    }
    std::printf("%s: %d fixes on the twin after it, %d published OK, %d said why\n",
                lose_it ? "odometry lost in the stretch" : "odometry kept", on_twin, ok_on_twin, said);
    EXPECT_GT(on_twin, 30);  // the scenario: the matcher stays on the twin
    EXPECT_EQ(ok_on_twin, 0);
    EXPECT_GT(said, on_twin / 2);
  }
}

// A start (or any re-acquisition) where a second fit explains about as many points as the fix: along a corridor whose
// wall has a fin every 1.5 m (beyond the sensor's 6 m range the view repeats) the place one period on is as good, so
// the track is published POOR ("a second fit ... away"), the offset in its covariance, however many fixes agree; in
// a room whose pillars fix the pose the start is confirmed as before. rival_ratio 0: the periodic start is OK.
TEST(Degeneracy, ReacquisitionWithASecondFitAsGoodStaysPoor) {
  const FloorPlan fins = fins_corridor();
  const FloorPlan room = fploc::testing::room_with_pillars();
  struct Case {
    const FloorPlan* plan;
    Pose2 start;
    double ratio;
    bool ambiguous;
  };
  for (const Case& c : {Case{&fins, {0.2, 0.8, 0}, 0.9, true}, Case{&fins, {0.2, 0.8, 0}, 0.0, false},
                        Case{&room, {5, 5, 0.3}, 0.9, false}}) {
    auto map = make_localization_map(*c.plan, "brute-force");
    localizer::Config cfg;
    cfg.uncertainty.rival_ratio = c.ratio;
    localizer::Localizer loc(*map.lookup, cfg);
    loc.set_pose(c.start, 1.0);
    fploc::testing::SynthOptions so = six_metre_sensor();
    std::vector<localizer::Pose> finals;
    int ok = 0, said = 0;
    double sigma_when_said = 0;
    for (int k = 0; k < 40; ++k) {
      const Pose2 truth{c.start.x + 0.05 * k, c.start.y, c.start.yaw};
      so.seed = uint32_t(k + 1);
      const auto s = loc.process(fploc::testing::synth_frame(*c.plan, truth, so, k * 100'000), &finals);
      ASSERT_TRUE(s.latest);
      if (s.latest->status == FitStatus::kOk) ++ok;
      if (loc.uncertainty().text.find("a second fit") != std::string::npos) {
        ++said;
        sigma_when_said = std::max(sigma_when_said, loc.uncertainty().sigma_max_m);
      }
    }
    std::printf("%s, rival_ratio %.1f: %d OK, %d said a second fit (1 sigma up to %.2f m)\n", c.plan == &fins ? "fins" : "room",
                c.ratio, ok, said, sigma_when_said);
    if (c.ambiguous) {
      EXPECT_EQ(ok, 0);
      EXPECT_GT(said, 30);
      EXPECT_GT(sigma_when_said, 1.0);  // a period along the corridor
    } else {
      EXPECT_GT(ok, 30);
      EXPECT_EQ(said, 0);
    }
  }
}

// The start of corridor seed 3's shelves world (notes, thirty-first round): a run of shelves stands across the corridor's
// end wall, its face 0.45 m in front of it. A pose 0.45 m towards the end puts the face on the wall and explains more
// points than the truth, whose hold along the corridor is three short jambs further on; the start's grid search takes
// it. The truth is a second fit that explains the jambs the fix leaves off the plan, and what it leaves off (the face)
// stands in front of the drawn wall: another explanation of the scan, so the start is POOR, although the truth explains
// under 80 % as many points as the fix (rival_ratio alone publishes the wrong start OK). Without the shelves, and in the
// room with pillars, the starts are OK as before.
TEST(Degeneracy, ShelvesAcrossACorridorEndAreNoEndWall) {
  FloorPlan corridor;
  corridor.elements.push_back(Element::segment({0, 0}, {30, 0}));
  corridor.elements.push_back(Element::segment({0, 2}, {30, 2}));
  corridor.elements.push_back(Element::segment({0, 0}, {0, 2}));
  corridor.elements.push_back(Element::segment({2.5, 2}, {2.5, 1.5}));  // jambs
  corridor.elements.push_back(Element::segment({3.7, 0}, {3.7, 0.5}));
  corridor.elements.push_back(Element::segment({5.2, 2}, {5.2, 1.6}));
  FloorPlan shelved = corridor;
  shelved.elements.push_back(Element::segment({0.45, 0.02}, {0.45, 1.98}));
  const FloorPlan room = fploc::testing::room_with_pillars();
  struct Case {
    const char* name;
    const FloorPlan *plan, *world;
    Pose2 start;
    int min_gained;
    bool wrong_start_ok;  // expected: the wrong start published OK
    int expect_ok_min;
  };
  for (const Case& c : {Case{"corridor, shelves across its end", &corridor, &shelved, {1.2, 1.0, 0}, UncertaintyConfig{}.rival_min_gained, false, 0},
                        Case{"... rival_ratio alone", &corridor, &shelved, {1.2, 1.0, 0}, 0, true, 0},
                        Case{"corridor, no shelves", &corridor, &corridor, {1.2, 1.0, 0}, -1, false, 30},
                        Case{"room with pillars", &room, &room, {5, 5, 0.3}, -1, false, 30}}) {
    auto map = make_localization_map(*c.plan, "brute-force");
    localizer::Config cfg;
    cfg.uncertainty.rival_min_gained = c.min_gained;
    localizer::Localizer loc(*map.lookup, cfg);
    loc.set_pose(c.start, 1.0);
    fploc::testing::SynthOptions so;
    so.beams = 720;
    so.noise_sigma = 0.005;
    so.max_range = 6;
    std::vector<localizer::Pose> finals;
    int ok = 0, false_ok = 0, said = 0, off = 0;
    for (int k = 0; k < 40; ++k) {
      const Pose2 truth{c.start.x + 0.03 * k, c.start.y, c.start.yaw};
      so.seed = uint32_t(k + 1);
      const auto s = loc.process(fploc::testing::synth_frame(*c.world, truth, so, k * 100'000), &finals);
      ASSERT_TRUE(s.latest);
      const double e = std::hypot(s.latest->pose.x - truth.x, s.latest->pose.y - truth.y);
      off += e > 0.3;
      if (s.latest->status == FitStatus::kOk) ++ok, false_ok += e > 0.3;
      said += loc.uncertainty().text.find("leaves off the plan") != std::string::npos;
    }
    std::printf("%s: %d OK, %d of them > 0.3 m off (%d frames off), %d said a second fit explains what the fix leaves\n", c.name,
                ok, false_ok, off, said);
    if (c.wrong_start_ok) {
      EXPECT_GT(false_ok, 20) << c.name;
    } else {
      EXPECT_EQ(false_ok, 0) << c.name;
    }
    EXPECT_GE(ok, c.expect_ok_min) << c.name;
  }
}

namespace {
// 21 points 8 cm apart along y at x (sensor frame): a wall seen side-on.
FeatureFrame points_along_y(double x) {
  FeatureFrame f;
  for (int i = -10; i <= 10; ++i) {
    Feature2 q;
    q.p = Eigen::Vector2d(x, 0.08 * i);
    f.points.push_back(q);
  }
  return f;
}
}  // namespace

TEST(Degeneracy, SeenThroughThePlanOnlyBeyondADrawnWall) {
  FloorPlan p;
  p.elements.push_back(Element::segment({2, -1}, {2, 1}));
  p.elements.push_back(Element::circle({0, 3}, 0.5));  // a pillar hides nothing here
  auto map = make_localization_map(p, "brute-force");
  const auto& g = map.lookup->geometry();
  EXPECT_TRUE(seen_through_plan(g, {0, 0}, {3, 0}, 0.1));
  EXPECT_FALSE(seen_through_plan(g, {0, 0}, {2.05, 0}, 0.1));  // on the wall, within the margin
  EXPECT_FALSE(seen_through_plan(g, {0, 0}, {1.5, 0}, 0.1));   // in front of it
  EXPECT_FALSE(seen_through_plan(g, {0, 0}, {3, 2}, 0.1));     // past its end
  EXPECT_FALSE(seen_through_plan(g, {0, 0}, {0, 5}, 0.1));
  // Point by point: the fix on the wall, a second fit 0.5 m back explains nothing more and loses the wall in front of it;
  // one 0.5 m forward puts the wall's points behind it.
  const FeatureFrame f = points_along_y(2.0);
  const FitComparison back = compare_fits(*map.lookup, f, Pose2{0, 0, 0}, Pose2{-0.5, 0, 0}, 0.1);
  EXPECT_EQ(back.fix_inliers, 21);
  EXPECT_EQ(back.gained, 0);
  EXPECT_EQ(back.lost, 21);
  EXPECT_EQ(back.lost_behind, 0);
  const FitComparison fwd = compare_fits(*map.lookup, f, Pose2{0, 0, 0}, Pose2{0.5, 0, 0}, 0.1);
  EXPECT_EQ(fwd.lost, 21);
  EXPECT_EQ(fwd.lost_behind, 21);
}

// A thick wall drawn with both faces (inner x = 2, outer x = 2.25), built 0.2 m in from where the plan draws it: its
// points (x = 1.8) are off the plan at the fix. A second fit 0.2 m on puts them on the inner face (structure it
// explains); one 0.45 m on puts them on the outer face, which the inner face hides from that fit's sensor: no
// structure (it was counted as such, and a room with a moved wall was published POOR for 25 s at its right pose).
TEST(Degeneracy, AFaceHiddenBehindADrawnWallExplainsNothing) {
  FloorPlan p;
  p.elements.push_back(Element::segment({2, -1}, {2, 1}));
  p.elements.push_back(Element::segment({2.25, -1}, {2.25, 1}));
  auto map = make_localization_map(p, "brute-force");
  const FeatureFrame f = points_along_y(1.8);
  const FitComparison inner = compare_fits(*map.lookup, f, Pose2{0, 0, 0}, Pose2{0.2, 0, 0}, 0.1);
  EXPECT_EQ(inner.gained, 21);
  EXPECT_EQ(inner.gained_hidden, 0);
  EXPECT_EQ(inner.gained_structure, 21);
  const FitComparison outer = compare_fits(*map.lookup, f, Pose2{0, 0, 0}, Pose2{0.45, 0, 0}, 0.1);
  EXPECT_EQ(outer.gained, 21);
  EXPECT_EQ(outer.gained_hidden, 21);
  EXPECT_EQ(outer.gained_structure, 0);
}

// As fins_corridor, the fins 0.7 m deep and every third left out (the view repeats every 4.5 m; one period on, 1.5 m,
// a look-alike that explains ~10 % fewer points).
FloorPlan fins_corridor_thirds() {
  FloorPlan plan;
  plan.elements.push_back(Element::segment({-20, 0}, {200, 0}));
  plan.elements.push_back(Element::segment({-20, 2}, {200, 2}));
  for (int i = 0; i < 140; ++i)
    if (i % 3 != 0) plan.elements.push_back(Element::segment({-20 + 1.5 * i, 2}, {-20 + 1.5 * i, 1.3}));
  return plan;
}

// The walk of the tests on it: 110 frames at 1 m/s along y = 0.8 from x = 0.2 (6 m sensor), the Localizer started at
// the first and, at frame 40, set at the truth plus `answer_offset` (a relocalizer's answer), with the robot's odometry
// if `odometry`; `frame(k, truth, step, horizontal error of the window's pose)` sees each frame.
template <class F>
void walk_fins_corridor(localizer::Localizer& loc, const FloorPlan& plan, const Pose2& answer_offset, bool odometry, F frame) {
  loc.set_pose({0.2, 0.8, 0}, 0.15);
  fploc::testing::SynthOptions so = six_metre_sensor();
  std::vector<localizer::Pose> finals;
  for (int k = 0; k < 110; ++k) {
    const Pose2 truth{0.2 + 0.1 * k, 0.8, 0};
    so.seed = uint32_t(k + 1);
    if (k == 40) loc.set_pose({truth.x + answer_offset.x, truth.y + answer_offset.y, truth.yaw + answer_offset.yaw}, 0.1);
    if (odometry) loc.add_odometry(k * 100'000, truth);
    const auto s = loc.process(fploc::testing::synth_frame(plan, truth, so, k * 100'000), &finals);
    ASSERT_TRUE(s.latest);
    frame(k, truth, s, std::hypot(s.latest->pose.x - truth.x, s.latest->pose.y - truth.y));
  }
}

// A fix on a look-alike while the odometry holds the truth (corridor s1 shelves, thirty-fourth round): a corridor whose
// upper wall has a 0.7 m fin every 1.5 m except every third one (plan and world alike), the matcher re-seeded one period
// (1.5 m) on. From there it tracks inside its gate: the walls agree, and where the plan lacks a fin the twin's view puts
// one of the world's, but it lacks fins the plan draws. The frame registered again from the dead-reckoned pose explains
// ~10 % more points than the twin's fix, so with dr_refit_ratio 1.05 it replaces the fix for the window and the tracker:
// agreeing with the dead reckoning, the frames are published OK on the truth. With dr_refit_ratio 0 the window holds
// the truth too (the twin's fixes, off the dead reckoning, carry their offset in their covariance) but every frame is
// published POOR. With the robot's odometry (add_odometry) no fix is refit: as with the ratio 0. In none is a pose OK
// far off.
TEST(Degeneracy, FixOnALookAlikeIsRefitFromTheDeadReckonedPose) {
  const FloorPlan plan = fins_corridor_thirds();
  auto map = make_localization_map(plan, "brute-force");
  struct Case {
    double ratio;
    bool odometry;
  };
  for (const Case c : {Case{1.05, false}, Case{0.0, false}, Case{1.05, true}}) {  // (the truth explains ~10 % more points than the twin)
    const double ratio = c.ratio;
    localizer::Config cfg;
    cfg.uncertainty.dr_refit_ratio = ratio;
    localizer::Localizer loc(*map.lookup, cfg);
    int after = 0, near = 0, ok = 0, on_twin = 0, false_ok = 0;
    // (the relocalizer's answer one period on)
    walk_fins_corridor(loc, plan, {1.5, 0, 0}, c.odometry, [&](int k, const Pose2& truth, const auto& s, double err) {
      if (s.latest->status == FitStatus::kOk && err > 0.3) ++false_ok;
      if (k < 60) return;
      ++after;
      near += err < 0.05;
      ok += s.latest->status == FitStatus::kOk;
      on_twin += std::abs(s.sfr.match.pose.x - truth.x - 1.5) < 0.1;
    });
    std::printf("dr_refit_ratio %.2f%s: of %d frames from 2 s after the re-seed, %d fixes on the twin, %d published within "
                "5 cm of the truth, %d OK; %d false OK\n", ratio, c.odometry ? " with the robot's odometry" : "", after, on_twin,
                near, ok, false_ok);
    EXPECT_EQ(false_ok, 0);
    EXPECT_GT(on_twin, after * 9 / 10);  // the scenario: the matcher stays on the twin
    EXPECT_GT(near, after * 9 / 10);
    if (ratio > 0 && !c.odometry) EXPECT_GT(ok, after * 8 / 10);
    else EXPECT_EQ(ok, 0);  // no refit: off, or the robot's odometry predicts the frames
  }
}

// A matcher started again at a wrong pose (a relocalizer's answer 8 m off) goes LOST and, lost, neither moves
// with the robot nor takes the window's pose; the dead reckoning (the LiDAR odometry carried from the last OK
// frames) goes on with the robot. With dr_reseed_when_lost the frame is registered from the dead-reckoned pose (still
// published LOST, in the window as a POOR frame, the window restarted there), and the matcher started again there (Localizer::process; the optimizer node's `reseed` output
// in the graphs): the frames are published OK on the truth again after the re-acquisition's confirmation. Without
// it the matcher stays LOST for the rest of the run (nothing else re-seeds it here: no relocalizer).
TEST(Degeneracy, ALostMatcherIsReseededFromTheDeadReckoning) {
  const FloorPlan plan = fins_corridor_thirds();
  auto map = make_localization_map(plan, "brute-force");
  for (const bool reseed : {true, false}) {
    localizer::Config cfg;
    cfg.uncertainty.dr_reseed_when_lost = reseed;
    localizer::Localizer loc(*map.lookup, cfg);
    int after = 0, near_ok = 0, lost = 0, false_ok = 0, reseeds = 0;
    // (a wrong answer: 8 m off, beyond every wall's reach)
    walk_fins_corridor(loc, plan, {0, 8, 0}, false, [&](int k, const Pose2&, const auto& s, double err) {
      if (s.latest->status == FitStatus::kOk && err > 0.3) ++false_ok;
      reseeds += s.latest->status_text == "re-seeded from the dead reckoning";
      if (k < 60) return;
      ++after;
      near_ok += s.latest->status == FitStatus::kOk && err < 0.05;
      lost += s.sfr.match.status == FitStatus::kLost;
    });
    std::printf("dr_reseed_when_lost %d: %d re-seeds; of %d frames from 2 s after the wrong pose, %d OK within 5 cm of the "
                "truth, %d LOST fixes; %d false OK\n", int(reseed), reseeds, after, near_ok, lost, false_ok);
    EXPECT_EQ(false_ok, 0);
    if (reseed) {
      EXPECT_GE(reseeds, 1);
      EXPECT_GT(near_ok, after * 9 / 10);
      EXPECT_EQ(lost, 0);
    } else {
      EXPECT_EQ(reseeds, 0);
      EXPECT_GT(lost, after * 9 / 10);  // the scenario: nothing else brings the matcher back
    }
  }
}

// A long stretch of right fixes published POOR for their weak fit alone (corridor s3 mixed with the column rule, the
// thirty-seventh round: a wall moved 0.2 m, 31-41 % of the points on the plan for 14 s): along the fins' corridor the
// world's lower wall stands 0.6 m beyond the drawn one from x = 3 to 30 (beyond the matcher's gate: its points are off
// the plan, the fins and the upper wall hold the fixes on the truth). The stretch freezes its anchor at x = 3, and with
// it the dead-reckoned 1-sigma grows by 2 % of the path, to ~0.55 m at x = 29, though the odometry stays within
// centimetres; there a relocalizer's answer one period on (1.5 m; the second-fit check off) is confirmed by its agreeing
// fixes and passes that gate: the tracker takes the twin's fixes OK 1.5 m off (the window, which the answer does not
// restart, holds the truth here and publishes POOR; in s3 mixed a re-seed had restarted it). With dr_weak_fit_sigma the
// weak fits that agree with the dead reckoning bound its covariance, and the twin's fixes are refused against it.
TEST(Degeneracy, WeakFitsAgreeingWithTheDeadReckoningBoundItsUncertainty) {
  const FloorPlan plan = fins_corridor();
  FloorPlan world;
  world.elements.push_back(Element::segment({-20, 0}, {3, 0}));
  world.elements.push_back(Element::segment({3, 0}, {3, -0.6}));
  world.elements.push_back(Element::segment({3, -0.6}, {30, -0.6}));
  world.elements.push_back(Element::segment({30, -0.6}, {30, 0}));
  world.elements.push_back(Element::segment({30, 0}, {200, 0}));
  for (size_t i = 1; i < plan.elements.size(); ++i) world.elements.push_back(plan.elements[i]);
  auto map = make_localization_map(plan, "brute-force");
  for (const double k : {1.0, 0.0}) {
    localizer::Config cfg;
    cfg.uncertainty.rival_ratio = 0;  // (the second fit one period on: ReacquisitionWithASecondFitAsGoodStaysPoor)
    cfg.uncertainty.dr_weak_fit_sigma = k;
    cfg.uncertainty.weak_fit_ratio = 0.6;  // (52 % of the points on the plan along the moved wall)
    localizer::Localizer loc(*map.lookup, cfg);
    loc.set_pose({0.2, 0.8, 0}, 0.15);
    fploc::testing::SynthOptions so = six_metre_sensor();
    std::vector<localizer::Pose> finals;
    int weak = 0, weak_right = 0, on_twin = 0, twin_ok = 0, false_ok = 0;
    for (int k2 = 0; k2 < 350; ++k2) {
      const Pose2 truth{0.2 + 0.1 * k2, 0.8, 0};
      so.seed = uint32_t(k2 + 1);
      if (k2 == 290) loc.set_pose({truth.x + 1.5, truth.y, truth.yaw}, 0.1);  // the relocalizer's answer, one period on
      const auto s = loc.process(fploc::testing::synth_frame(world, truth, so, k2 * 100'000), &finals);
      ASSERT_TRUE(s.latest);
      const double err = std::hypot(s.latest->pose.x - truth.x, s.latest->pose.y - truth.y);
      if (loc.uncertainty().weak_fit) {
        ++weak;
        weak_right += std::hypot(s.sfr.match.pose.x - truth.x, s.sfr.match.pose.y - truth.y) < 0.05;
      }
      if (k2 > 290 && s.sfr.match.status == FitStatus::kOk && std::abs(s.sfr.match.pose.x - truth.x - 1.5) < 0.1) {
        ++on_twin;
        twin_ok += loc.uncertainty().status == FitStatus::kOk;  // the tracker takes the fix 1.5 m off as OK
      }
      if (s.latest->status == FitStatus::kOk && err > 0.3) ++false_ok;
    }
    std::printf("dr_weak_fit_sigma %.0f: %d weak fits (%d within 5 cm), %d fixes on the twin after its answer, %d of them "
                "OK for the tracker; %d false OK\n", k, weak, weak_right, on_twin, twin_ok, false_ok);
    EXPECT_GT(weak, 200);  // the scenario: a long stretch of right weak fits, then the matcher on the twin
    EXPECT_GT(weak_right, weak * 9 / 10);
    EXPECT_GT(on_twin, 40);
    EXPECT_EQ(false_ok, 0);  // (the window, not restarted by the answer, holds the truth here: published POOR)
    if (k > 0) EXPECT_EQ(twin_ok, 0);
    else EXPECT_GT(twin_ok, on_twin / 2);
  }
}
