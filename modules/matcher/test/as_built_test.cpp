// As-built model of the floor-plan terms (as_built.h): walls that stand a few cm from where the plan draws
// them. One near wall moved by 6 cm, seen with most of the points, pulls the plain registration by most of
// its offset; with the per-wall end offsets eliminated every wall counts about the same and the moved one
// only by a bounded share. On a world that is its plan the model changes nothing measurable.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <utility>

#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/matcher/plan_terms.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::matcher;

namespace {

// The plan with segment i moved by `d` along its left normal.
FloorPlan moved(const FloorPlan& plan, size_t i, double d) {
  FloorPlan w = plan;
  Element& e = w.elements[i];
  const Eigen::Vector2d u = (e.b - e.a).normalized();
  const Eigen::Vector2d n(-u.y(), u.x());
  e.a += d * n;
  e.b += d * n;
  return w;
}

// An as-built world: every segment's ends displaced by their own N(0, sigma) along the segment's normal (seeded).
FloorPlan as_built_world(FloorPlan w, uint32_t seed, double sigma = 0.05) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (Element& e : w.elements) {
    if (e.kind != ElementKind::kSegment) continue;
    const Eigen::Vector2d u = (e.b - e.a).normalized(), nrm(-u.y(), u.x());
    e.a += g(rng) * nrm;
    e.b += g(rng) * nrm;
  }
  return w;
}

MatcherConfig config(bool as_built) {
  MatcherConfig c;
  c.max_iterations = 30;
  c.max_rounds = 8;
  c.max_points = 0;
  if (as_built) c.as_built.sigma_m = 0.02;
  return c;
}

}  // namespace

TEST(AsBuilt, NearMovedWallPullsLess) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  // Segment 1: the south wall y = 0 (x 5..20), left normal +y (into the room). Sensor 1 m from it.
  const FloorPlan world = moved(plan, 1, 0.06);
  auto map = make_localization_map(plan, "annf-exact");
  fploc::testing::SynthOptions so;
  so.beams = 1440;
  so.max_range = 30;
  so.noise_sigma = 0.005;
  for (const Pose2 truth : {Pose2{10.0, 1.0, 0.3}, Pose2{17.0, 1.2, -2.0}}) {
    const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
    const MatchResult plain = register_frame(*map.lookup, f, truth, config(false));
    const MatchResult ab = register_frame(*map.lookup, f, truth, config(true));
    ASSERT_EQ(plain.status, FitStatus::kOk);
    ASSERT_EQ(ab.status, FitStatus::kOk);
    const double e_plain = std::hypot(plain.pose.x - truth.x, plain.pose.y - truth.y);
    const double e_ab = std::hypot(ab.pose.x - truth.x, ab.pose.y - truth.y);
    EXPECT_GT(e_plain, 0.02) << "the near wall's 6 cm should pull the plain fit by centimetres";
    EXPECT_LT(e_ab, 0.5 * e_plain) << "plain " << e_plain << " as-built " << e_ab;
  }
}

TEST(AsBuilt, WorldAsDrawnUnchanged) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  auto map = make_localization_map(plan, "annf-exact");
  fploc::testing::SynthOptions so;
  so.max_range = 30;
  so.noise_sigma = 0.005;
  for (const Pose2 truth : {Pose2{3.0, 5.0, 0.2}, Pose2{16.0, 2.5, -1.0}, Pose2{10.0, 8.0, 2.0}}) {
    const FeatureFrame f = fploc::testing::synth_frame(plan, truth, so);
    const Pose2 guess{truth.x + 0.05, truth.y - 0.04, truth.yaw + 0.01};
    const MatchResult ab = register_frame(*map.lookup, f, guess, config(true));
    ASSERT_EQ(ab.status, FitStatus::kOk);
    EXPECT_LT(std::hypot(ab.pose.x - truth.x, ab.pose.y - truth.y), 0.003);
    EXPECT_LT(std::abs(ab.pose.yaw - truth.yaw), 0.002);
  }
}

// A 30 m corridor, 2 m wide, its east end wall glass (no returns), a cabinet's 0.9 m face 22 deg askew to that end
// centred at (face_x, 1) (behind the drawn line beyond 30 m, in front of it short of 30 m); and the scans of it.
namespace {
struct GlassEnd {
  FloorPlan plan, world;
  Eigen::Vector2d face;  // the face's centre
};
GlassEnd glass_end_corridor(double face_x) {
  GlassEnd g;
  g.plan.elements.push_back(Element::segment({0, 0}, {30, 0}));
  g.plan.elements.push_back(Element::segment({0, 2}, {30, 2}));
  g.plan.elements.push_back(Element::segment({0, 0}, {0, 2}));
  g.plan.elements.push_back(Element::segment({30, 0}, {30, 2}));
  g.world = g.plan;
  g.world.elements.pop_back();  // the east end: glass
  const Eigen::Vector2d c(face_x, 1.0), u(std::sin(22 * M_PI / 180), std::cos(22 * M_PI / 180));
  g.world.elements.push_back(Element::segment(c - 0.45 * u, c + 0.45 * u));
  g.face = c;
  return g;
}
fploc::testing::SynthOptions glass_end_scan() {
  fploc::testing::SynthOptions so;
  so.beams = 1440;
  so.max_range = 30;
  so.noise_sigma = 0.005;
  return so;
}
// A tracking frame (the prediction at the truth as a weak prior) registered with the as-built model, without and with
// the askew rule (askew_max_m 0.1).
std::pair<MatchResult, MatchResult> tracked_without_and_with_askew(const NearestLookup& lookup, const FeatureFrame& f,
                                                                    const Pose2& truth) {
  PosePrior prior;
  prior.pose = truth;
  prior.sqrt_info = Eigen::Vector3d(1e-3, 1e-3, 1e-3);
  MatcherConfig plain = config(true), askew = config(true);
  askew.askew_max_m = 0.1;
  return {register_frame(lookup, f, truth, plain, &prior), register_frame(lookup, f, truth, askew, &prior)};
}
}  // namespace

// A corridor whose east end wall is glass (no returns) with a cabinet behind it: the cabinet's face (0.9 m of
// the 2 m wall, 22 deg askew, 1-35 cm behind the drawn line) and the west end wall 10-20 m away are all that
// holds the position along the corridor. The face's points do not lie on one line with the wall (their spread
// about the wall's fitted offsets is ~10 cm against the 4 cm point sigma), so they pull with a share scaled down
// (AsBuiltModel::max_spread_sigmas), not as a whole wall standing off its place.
TEST(AsBuilt, AFaceSeenThroughGlassDoesNotPullAsAWall) {
  const GlassEnd g = glass_end_corridor(30.18);
  const FloorPlan& world = g.world;
  auto map = make_localization_map(g.plan, "annf-exact");
  const fploc::testing::SynthOptions so = glass_end_scan();
  for (const Pose2 truth : {Pose2{20.0, 1.0, 0.0}, Pose2{22.0, 0.7, 0.5}, Pose2{18.0, 1.3, 2.8}}) {
    const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
    MatcherConfig whole = config(true), bounded = config(true), gated = config(true);
    bounded.as_built.max_spread_sigmas = 1.0;
    gated.as_built.max_spread_sigmas = 1.0;
    gated.as_built.max_askew_m = 0.1;  // the face's own line meets the wall's ends metres apart
    const MatchResult a = register_frame(*map.lookup, f, truth, whole);
    const MatchResult b = register_frame(*map.lookup, f, truth, bounded);
    const MatchResult g = register_frame(*map.lookup, f, truth, gated);
    ASSERT_EQ(a.status, FitStatus::kOk);
    ASSERT_EQ(b.status, FitStatus::kOk);
    ASSERT_EQ(g.status, FitStatus::kOk);
    const double e_whole = std::abs(a.pose.x - truth.x), e_bounded = std::abs(b.pose.x - truth.x);
    EXPECT_GT(e_whole, 0.005) << "as a whole wall the face should pull the fit along the corridor";
    EXPECT_LT(e_bounded, 0.7 * e_whole) << "whole share " << e_whole << " bounded " << e_bounded;
    EXPECT_LT(std::abs(g.pose.x - truth.x), 0.7 * e_whole) << "the gate should still bound the face's share";
  }
}

// An as-built world at sigma 5 cm against the model's 2 cm prior: every wall end displaced by its own
// N(0, 5 cm) along the wall's normal (seeded). A displaced wall's points can spread about the offsets the prior
// holds small, so the spread rule alone takes some real walls' shares down as if they were faces seen through
// glass (here: one fit of eighteen moves by 3 mm). Their own lines turn against their walls by no more than the
// displacements do, so with the gate (max_askew_m) every wall keeps its whole share: the fit is the one without
// the spread rule.
TEST(AsBuilt, WallsAFewCentimetresOffKeepTheirShareWithTheGate) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  auto map = make_localization_map(plan, "annf-exact");
  fploc::testing::SynthOptions so;
  so.beams = 720;
  so.noise_sigma = 0.005;
  int differs = 0, frames = 0;
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const FloorPlan world = as_built_world(plan, seed);
    for (const Pose2 truth : {Pose2{10.0, 4.0, 0.4}, Pose2{3.0, 2.0, -1.0}, Pose2{17.0, 8.0, 2.0}}) {
      const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
      MatcherConfig plain = config(true), spread = config(true), gated = config(true);
      spread.as_built.max_spread_sigmas = gated.as_built.max_spread_sigmas = 1.0;
      gated.as_built.max_askew_m = 0.1;
      const MatchResult p = register_frame(*map.lookup, f, truth, plain);
      const MatchResult s = register_frame(*map.lookup, f, truth, spread);
      const MatchResult g = register_frame(*map.lookup, f, truth, gated);
      ASSERT_EQ(p.status, FitStatus::kOk);
      ASSERT_EQ(g.status, FitStatus::kOk);
      ++frames;
      const double ds = std::hypot(s.pose.x - p.pose.x, s.pose.y - p.pose.y);
      const double dg = std::hypot(g.pose.x - p.pose.x, g.pose.y - p.pose.y);
      std::printf("seed %u: spread moves the fit %.2f mm, gated %.2f mm\n", seed, 1e3 * ds, 1e3 * dg);
      if (ds > 1e-4) ++differs;
      EXPECT_LT(dg, 1e-4) << "seed " << seed;
    }
  }
  EXPECT_GT(differs, 0) << "the spread rule alone should take a displaced wall's share in " << frames << " frames";
}

// The as-built term evaluated through the walls' moments (AsBuiltModel::per_wall) gives the cost, gradient
// and Gauss-Newton matrix of the per-point evaluation: exactly at the pose it was prepared at, and within
// what the points' frozen position along their wall allows 2 cm / 0.5 deg away from it.
TEST(AsBuilt, PerWallEvaluationMatchesPerPoint) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  const FloorPlan world = moved(moved(plan, 1, 0.04), 3, -0.03);
  auto map = make_localization_map(plan, "annf-exact");
  fploc::testing::SynthOptions so;
  so.beams = 720;
  so.noise_sigma = 0.005;
  so.clutter_fraction = 0.1;
  const Pose2 truth{10.0, 4.0, 0.4};
  const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
  AssignOptions ao;
  std::vector<Assignment> as;
  assign(*map.lookup, f, truth, ao, &as);
  ASSERT_GT(as.size(), 100u);
  AsBuiltModel per_point, per_wall;
  per_point.sigma_m = per_wall.sigma_m = 0.02;
  per_point.per_wall = false;
  const double x0[3] = {truth.x + 0.01, truth.y - 0.01, truth.yaw + 0.002};
  auto tp = make_frame_term(x0, *map.lookup, f, as, "cauchy", 0.05, 1.0, true, &per_point);
  auto tw = make_frame_term(x0, *map.lookup, f, as, "cauchy", 0.05, 1.0, true, &per_wall);
  ASSERT_TRUE(tp && tw);
  auto eval = [](ceres::CostFunction* c, const double* x, Eigen::Matrix3d* H, Eigen::Vector3d* g) {
    double r[4], j[12];
    const double* params[1] = {x};
    double* jac[1] = {j};
    EXPECT_TRUE(c->Evaluate(params, r, jac));
    Eigen::Map<const Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> J(j);
    const Eigen::Map<const Eigen::Vector4d> R(r);
    *H = J.transpose() * J;
    *g = J.transpose() * R;
    return R.squaredNorm();
  };
  for (const double dx : {0.0, 0.02}) {
    const double x[3] = {x0[0] + dx, x0[1] - dx, x0[2] + (dx > 0 ? 0.5 * M_PI / 180 : 0.0)};
    Eigen::Matrix3d Hp, Hw;
    Eigen::Vector3d gp, gw;
    const double cp = eval(tp.get(), x, &Hp, &gp), cw = eval(tw.get(), x, &Hw, &gw);
    const double tol = dx == 0 ? 1e-9 : 0.02;  // relative
    EXPECT_NEAR(cw, cp, tol * cp + 1e-12) << "dx " << dx;
    EXPECT_LT((Hw - Hp).norm(), tol * Hp.norm()) << "dx " << dx;
    EXPECT_LT((gw - gp).norm(), tol * (gp.norm() + 1e-3 * Hp.norm())) << "dx " << dx;
  }
}

// Askew faces (MatcherConfig::askew_max_m, AssignOptions::askew_max_m): the corridor of the test above, its
// east end wall glass, with a cabinet standing 20 cm in front of it (as on the corridor's glass world, seed 2:
// a 0.9 m face 22 deg askew to the drawn wall, its only returns near that wall's line). Taken for the end wall
// (the as-built model gives every wall a share, whatever its points' number) it holds the position along the
// corridor against the west end; its points lie on a line that turns against the wall by metres between the
// wall's ends, so with the rule they are left out of the frame: the fit is held by the walls that are there.
// The rule is judged at the tracking guess only (a prior given); its yaw error is taken out first.
TEST(AskewFaces, AFaceWhereAGlassWallIsDrawnIsLeftOut) {
  const GlassEnd g = glass_end_corridor(29.8);
  const FloorPlan& world = g.world;
  const Eigen::Vector2d c = g.face;
  auto map = make_localization_map(g.plan, "annf-exact");
  const fploc::testing::SynthOptions so = glass_end_scan();
  for (const Pose2 truth : {Pose2{20.0, 1.0, 0.0}, Pose2{22.0, 0.7, 0.5}, Pose2{18.0, 1.3, 2.8}}) {
    const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
    const auto [a, b] = tracked_without_and_with_askew(*map.lookup, f, truth);
    ASSERT_EQ(a.status, FitStatus::kOk);
    ASSERT_EQ(b.status, FitStatus::kOk);
    const double e_whole = std::abs(a.pose.x - truth.x), e_askew = std::abs(b.pose.x - truth.x);
    EXPECT_GT(e_whole, 0.005) << "as the end wall the face should pull the fit along the corridor";
    EXPECT_LT(e_askew, 0.25 * e_whole) << "whole " << e_whole << " askew left out " << e_askew;
    // The selection: the face's points are out, every wall's point in, also from a guess 0.3 deg off in yaw (every
    // wall's points turned alike; a tracking guess is good to a tenth of that). 1.5 deg off (the walls' points 26 cm
    // off at the face, partly beyond the gate) the face may stay, but no wall is left out.
    for (const double dyaw : {0.0, 0.3 * M_PI / 180, 1.5 * M_PI / 180}) {
      AssignOptions ao;
      ao.gate_m = 0.3;
      ao.askew_max_m = 0.1;
      std::vector<SampledPoint> sel;
      const Pose2 guess{truth.x, truth.y, truth.yaw + dyaw};
      select_points(*map.lookup, f, guess, ao, &sel);
      int face = 0, walls = 0, face_all = 0, walls_all = 0;
      const double cy = std::cos(truth.yaw), sy = std::sin(truth.yaw);
      auto world = [&](const Feature2& p) {
        return Eigen::Vector2d(cy * p.p.x() - sy * p.p.y() + truth.x, sy * p.p.x() + cy * p.p.y() + truth.y);
      };
      auto at_face = [&](const Feature2& p) {  // within the gate (0.3 m) of the drawn end wall
        const Eigen::Vector2d w = world(p);
        return w.x() > 29.7 && w.y() > 0.3 && w.y() < 1.7;
      };
      auto on_wall = [&](const Feature2& p) { return (world(p) - c).norm() > 0.6; };
      for (const Feature2& p : f.points) {
        face_all += at_face(p);
        walls_all += on_wall(p);
      }
      for (const SampledPoint& s : sel) {
        face += at_face(f.points[size_t(s.point)]);
        walls += on_wall(f.points[size_t(s.point)]);
      }
      ASSERT_GT(face_all, 10);
      if (dyaw < 1 * M_PI / 180) {
        EXPECT_EQ(face, 0) << "yaw off by " << dyaw;
      }
      EXPECT_EQ(walls, walls_all) << "yaw off by " << dyaw;
    }
  }
}

// An as-built world at sigma 5 cm (every wall end displaced by its own N(0, 5 cm) along the wall's normal,
// seeded) and a wall moved 25 cm along its normal: their points' lines turn against their walls by no more than
// the displacements do, so the rule leaves every point in (the fit is the one without it), also from a guess
// whose yaw is off by a degree.
TEST(AskewFaces, DisplacedWallsAreKept) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  auto map = make_localization_map(plan, "annf-exact");
  fploc::testing::SynthOptions so;
  so.beams = 720;
  so.noise_sigma = 0.005;
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const FloorPlan world = as_built_world(moved(plan, 1, 0.25), seed);
    for (const Pose2 truth : {Pose2{10.0, 4.0, 0.4}, Pose2{3.0, 2.0, -1.0}, Pose2{17.0, 8.0, 2.0}}) {
      const FeatureFrame f = fploc::testing::synth_frame(world, truth, so);
      for (const double dyaw : {0.0, 1.0 * M_PI / 180}) {
        AssignOptions ao;
        ao.gate_m = 0.3;
        ao.askew_max_m = 0.1;
        std::vector<SampledPoint> sel;
        select_points(*map.lookup, f, Pose2{truth.x, truth.y, truth.yaw + dyaw}, ao, &sel);
        EXPECT_EQ(sel.size(), f.points.size()) << "seed " << seed << " yaw off by " << dyaw;
      }
      const auto [p, g] = tracked_without_and_with_askew(*map.lookup, f, truth);
      ASSERT_EQ(p.status, FitStatus::kOk);
      ASSERT_EQ(g.status, FitStatus::kOk);
      EXPECT_LT(std::hypot(g.pose.x - p.pose.x, g.pose.y - p.pose.y), 1e-6) << "seed " << seed;
    }
  }
}
