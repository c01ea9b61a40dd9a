// AMCL baseline: the maths (KLD bound, bins/clusters, resampling, motion model statistics), the
// likelihood field, tracking and global localisation on synthetic plans (ray-cast scans with noise and
// clutter, odometry with bias and noise), bad input, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numeric>

#include "fploc/amcl/amcl.h"
#include "fploc/amcl/odometry.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::amcl;

namespace {

constexpr double kDeg = M_PI / 180.0;

std::vector<Eigen::Vector2d> points_of(const FeatureFrame& f) {
  std::vector<Eigen::Vector2d> p;
  for (const auto& q : f.points) p.push_back(q.p);
  return p;
}

double yaw_err(double a, double b) { return std::abs(wrap_angle(a - b)); }

// Closed loop of poses (heading along the path) through the given corners, `step` metres apart; at a
// corner the sensor turns in place, 0.1 rad per scan (a dolly pushed round a corner).
std::vector<Pose2> loop_path(const std::vector<Eigen::Vector2d>& corners, double step, int laps = 1) {
  std::vector<Pose2> out;
  for (int l = 0; l < laps; ++l)
    for (size_t i = 0; i < corners.size(); ++i) {
      const Eigen::Vector2d a = corners[i], b = corners[(i + 1) % corners.size()];
      const double len = (b - a).norm(), yaw = std::atan2(b.y() - a.y(), b.x() - a.x());
      if (!out.empty()) {
        const double from = out.back().yaw, turn = wrap_angle(yaw - from);
        const int n = int(std::ceil(std::abs(turn) / 0.1));
        for (int k = 1; k < n; ++k) out.push_back({a.x(), a.y(), wrap_angle(from + turn * k / n)});
      }
      for (double s = 0; s < len; s += step) {
        const Eigen::Vector2d p = a + (b - a) * (s / len);
        out.push_back({p.x(), p.y(), yaw});
      }
    }
  return out;
}

struct RunResult {
  std::vector<Pose2> truth, est;
  std::vector<Eigen::Matrix3d> cov;
  std::vector<double> err_xy, err_yaw;
  std::vector<int> particles;
  int updates = 0;
};

// Drives a filter along `path`: scans ray-cast from the true pose, odometry = simulated wheel odometry
// (nav2 defaults of the simulated odometry: 2 % scale error, 1 deg/m drift, noise).
// `odom_path` (default: the path) is what the odometry sees (differs from the path for a kidnapped robot).
RunResult drive(Amcl& f, const FloorPlan& plan, const std::vector<Pose2>& path, const WheelOdometryConfig& wc,
                const fploc::testing::SynthOptions& so_in, const std::vector<Pose2>* odom_path = nullptr) {
  RunResult r;
  WheelOdometrySim odo(wc);
  fploc::testing::SynthOptions so = so_in;
  for (size_t k = 0; k < path.size(); ++k) {
    so.seed = so_in.seed + uint32_t(k);
    const FeatureFrame fr = fploc::testing::synth_frame(plan, path[k], so);
    const LaserScan scan = points_to_scan(points_of(fr), 360, 0.0, 100.0);
    const Pose2 o = odo.update(odom_path ? (*odom_path)[k] : path[k]);
    const StepInfo info = f.process(o, scan);
    EXPECT_TRUE(info.problem.empty()) << info.problem;
    if (info.updated) ++r.updates;
    const Pose2 e = f.pose_at(o);
    r.truth.push_back(path[k]);
    r.est.push_back(e);
    r.cov.push_back(f.stats().cov);
    r.err_xy.push_back(std::hypot(e.x - path[k].x, e.y - path[k].y));
    r.err_yaw.push_back(yaw_err(e.yaw, path[k].yaw));
    r.particles.push_back(int(f.particles().size()));
  }
  return r;
}

double max_from(const std::vector<double>& v, size_t from) {
  double m = 0;
  for (size_t i = from; i < v.size(); ++i) m = std::max(m, v[i]);
  return m;
}

double mean_from(const std::vector<double>& v, size_t from) {
  double m = 0;
  for (size_t i = from; i < v.size(); ++i) m += v[i];
  return v.size() > from ? m / double(v.size() - from) : 0.0;
}

// First index from which the error stays below `bound` to the end (size() if never).
size_t settled_at(const std::vector<double>& err, double bound) {
  size_t k = err.size();
  while (k > 0 && err[k - 1] < bound) --k;
  return k;
}

// "Tracking" below: the likelihood field pulls a particle back only while its beams end within a few
// sigma_hit of the walls, so a tracking filter stays within 2 sigma_hit (0.4 m) and a lost one is metres
// off; 10 deg of yaw at 5 m range is 0.9 m of scan displacement, far outside the kernel.
constexpr double kTrackXY = 0.4, kTrackYaw = 10 * M_PI / 180.0;

// An L-shaped room (no symmetry) with a square pillar.
FloorPlan l_room() {
  FloorPlan p;
  auto seg = [&](double x1, double y1, double x2, double y2) { p.elements.push_back(Element::segment({x1, y1}, {x2, y2})); };
  seg(0, 0, 9, 0);
  seg(9, 0, 9, 4);
  seg(9, 4, 4, 4);
  seg(4, 4, 4, 8);
  seg(4, 8, 0, 8);
  seg(0, 8, 0, 0);
  seg(6.0, 1.5, 6.6, 1.5);
  seg(6.6, 1.5, 6.6, 2.1);
  seg(6.6, 2.1, 6.0, 2.1);
  seg(6.0, 2.1, 6.0, 1.5);
  p.source = "synthetic-l-room";
  return p;
}

Eigen::Matrix3d diag_cov(double sxy, double syaw) {
  return Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
}

}  // namespace

// ---- KLD ------------------------------------------------------------------------------------------

TEST(Kld, MatchesChiSquareQuantiles) {
  // Fox's bound n = chi2_{k-1, 1-delta} / (2 err) with the Wilson–Hilferty approximation; compare with
  // tabulated chi-square quantiles (0.99: 10 dof 23.209, 100 dof 135.807; 0.95: 30 dof 43.773).
  const double z99 = 2.3263478740, z95 = 1.6448536270;
  EXPECT_NEAR(kld_limit(11, 0.05, z99, 1, 1000000), 23.209 / 0.1, 0.01 * 232.09);
  EXPECT_NEAR(kld_limit(101, 0.05, z99, 1, 1000000), 135.807 / 0.1, 0.005 * 1358.07);
  EXPECT_NEAR(kld_limit(31, 0.01, z95, 1, 1000000), 43.773 / 0.02, 0.005 * 2188.65);
}

TEST(Kld, ClampsAndMonotone) {
  EXPECT_EQ(kld_limit(0, 0.05, 0.99, 500, 2000), 2000);
  EXPECT_EQ(kld_limit(1, 0.05, 0.99, 500, 2000), 2000);
  EXPECT_EQ(kld_limit(2, 0.05, 0.99, 500, 2000), 500);      // few bins: min_particles
  EXPECT_EQ(kld_limit(100000, 0.05, 0.99, 500, 2000), 2000);
  int last = 0;
  for (int k = 2; k < 500; ++k) {
    const int n = kld_limit(k, 0.05, 0.99, 1, 1000000);
    EXPECT_GE(n, last);
    last = n;
  }
  // nav2's defaults (pf_z = 0.99 used as the quantile itself): the bound passes min_particles = 500 at
  // 43 occupied bins (42: 10 * 41 * (1 - 2/369 + 0.99 sqrt(2/369))^3 = 498.8).
  EXPECT_EQ(kld_limit(42, 0.05, 0.99, 500, 2000), 500);
  EXPECT_GT(kld_limit(43, 0.05, 0.99, 500, 2000), 500);
}

// ---- bins, clusters ------------------------------------------------------------------------------

TEST(Bins, CountsAndClusters) {
  BinSet b(0.5, 10 * kDeg);
  EXPECT_TRUE(b.insert(0.1, 0.1, 0.0));
  EXPECT_FALSE(b.insert(0.2, 0.3, 0.05));
  EXPECT_TRUE(b.insert(0.6, 0.1, 0.0));   // neighbour bin
  EXPECT_TRUE(b.insert(5.0, 5.0, 0.0));   // far away
  EXPECT_EQ(b.size(), 3);
  EXPECT_EQ(b.cluster(), 2);
  EXPECT_EQ(b.cluster_of(0.1, 0.1, 0.0), b.cluster_of(0.6, 0.1, 0.0));
  EXPECT_NE(b.cluster_of(0.1, 0.1, 0.0), b.cluster_of(5.0, 5.0, 0.0));
  // Yaw bins are adjacent across +-pi.
  BinSet w(0.5, 10 * kDeg);
  w.insert(1, 1, M_PI - 0.01);
  w.insert(1, 1, -M_PI + 0.01);
  EXPECT_EQ(w.size(), 2);
  EXPECT_EQ(w.cluster(), 1);
  // Many inserts (table growth) keep every bin.
  BinSet g(0.5, 10 * kDeg);
  for (int i = 0; i < 5000; ++i) EXPECT_TRUE(g.insert(i * 0.5 + 0.25, 0.25, 0));
  EXPECT_EQ(g.size(), 5000);
  EXPECT_FALSE(g.insert(1234 * 0.5 + 0.3, 0.3, 0.01));
}

TEST(Bins, ClusterStatsBestClusterAndCircularMean) {
  std::vector<Particle> ps;
  for (int i = 0; i < 30; ++i) ps.push_back({1.0 + 0.01 * i, 1.0, M_PI - 0.02 + 0.04 * (i % 2), 0.02});  // weight 0.6
  for (int i = 0; i < 40; ++i) ps.push_back({6.0, 6.0 + 0.01 * i, 0.5, 0.01});                          // weight 0.4
  BinSet b(0.5, 10 * kDeg);
  const SetStats st = cluster_stats(ps, b, 0.5);
  ASSERT_EQ(st.clusters.size(), 2u);
  ASSERT_GE(st.best, 0);
  const Cluster& best = st.clusters[size_t(st.best)];
  EXPECT_NEAR(best.weight, 0.6, 1e-12);
  EXPECT_EQ(best.count, 30);
  EXPECT_NEAR(best.mean.x, 1.145, 1e-9);
  EXPECT_NEAR(best.mean.y, 1.0, 1e-12);
  EXPECT_LT(yaw_err(best.mean.yaw, M_PI), 1e-9);  // circular mean across +-pi, not 0
  EXPECT_LT(best.cov(2, 2), 1e-3);
  EXPECT_FALSE(st.converged);  // 7 m apart
  EXPECT_NEAR(st.mean.x, 0.6 * 1.145 + 0.4 * 6.0, 1e-9);
}

// ---- resampling ----------------------------------------------------------------------------------

TEST(Resampling, LowVarianceCountsWithinOneOfExpected) {
  const std::vector<double> w = {0.05, 0.0, 0.15, 0.3, 0.5};
  for (double u0 : {0.0, 0.37, 0.999}) {
    const auto idx = low_variance_indices(w, 1000, u0);
    ASSERT_EQ(idx.size(), 1000u);
    std::vector<int> count(w.size(), 0);
    for (int i : idx) count[size_t(i)]++;
    for (size_t i = 0; i < w.size(); ++i) EXPECT_LE(std::abs(count[i] - 1000 * w[i]), 1.0) << i << " u0 " << u0;
    EXPECT_EQ(count[1], 0);
  }
}

TEST(Resampling, SampleIndexInverseOfCumulative) {
  const std::vector<double> c = {0.0, 0.25, 0.25, 0.75, 1.0};  // weights .25 0 .5 .25
  EXPECT_EQ(sample_index(c, 0.0), 0);
  EXPECT_EQ(sample_index(c, 0.2499), 0);
  EXPECT_EQ(sample_index(c, 0.25), 2);  // the zero-weight particle is never chosen
  EXPECT_EQ(sample_index(c, 0.7), 2);
  EXPECT_EQ(sample_index(c, 0.75), 3);
  EXPECT_EQ(sample_index(c, 0.99999), 3);
  EXPECT_EQ(sample_index(c, 1.0), 3);   // rounding at the top end stays in range
}

// ---- motion model --------------------------------------------------------------------------------

TEST(MotionModel, NoNoiseMovesEveryParticleByTheOdometryIncrement) {
  Config c;
  c.alpha1 = c.alpha2 = c.alpha3 = c.alpha4 = 0;
  Amcl f(fploc::testing::room_with_pillars(), c);
  const Pose2 start{5, 5, 0.7};
  f.init_pose(start, Eigen::Matrix3d::Zero());
  const Pose2 o1{-2, 3, 2.0}, o2{-1.6, 3.3, 2.3};
  f.motion_update(o1, o2);
  const Pose2 want = compose(start, between(o1, o2));
  for (const auto& p : f.particles()) {
    EXPECT_NEAR(p.x, want.x, 1e-12);
    EXPECT_NEAR(p.y, want.y, 1e-12);
    EXPECT_NEAR(yaw_err(p.yaw, want.yaw), 0, 1e-12);
  }
}

TEST(MotionModel, NoiseMatchesTheAlphas) {
  // Straight 1 m: sd(trans) = sqrt(alpha3) * 1, rot1 and rot2 each sqrt(alpha2) * 1 -> sd(yaw) = sqrt(2 alpha2).
  Config c;
  c.alpha1 = 0.1;
  c.alpha2 = 0.02;
  c.alpha3 = 0.05;
  c.alpha4 = 0.3;
  c.max_particles = 20000;
  Amcl f(fploc::testing::room_with_pillars(), c);
  f.init_pose({5, 5, 0}, Eigen::Matrix3d::Zero());
  f.motion_update({0, 0, 0}, {1, 0, 0});
  const auto& ps = f.particles();
  double sd = 0, sy = 0, md = 0;
  for (const auto& p : ps) md += std::hypot(p.x - 5, p.y - 5);
  md /= double(ps.size());
  for (const auto& p : ps) {
    const double d = std::hypot(p.x - 5, p.y - 5) - md;
    sd += d * d;
    sy += p.yaw * p.yaw;
  }
  sd = std::sqrt(sd / double(ps.size()));
  sy = std::sqrt(sy / double(ps.size()));
  // 20000 samples: the sample sd is within ~0.5 % (1 sigma) of the true one; allow 3 %.
  EXPECT_NEAR(md, 1.0, 0.01);
  EXPECT_NEAR(sd, std::sqrt(0.05), 0.03 * std::sqrt(0.05));
  EXPECT_NEAR(sy, std::sqrt(2 * 0.02), 0.03 * std::sqrt(0.04));
}

TEST(MotionModel, RotationInPlaceUsesAlpha1AndAlpha4) {
  Config c;
  c.alpha1 = 0.1;
  c.alpha2 = 0.0;
  c.alpha3 = 0.0;
  c.alpha4 = 0.05;
  c.max_particles = 20000;
  Amcl f(fploc::testing::room_with_pillars(), c);
  f.init_pose({5, 5, 0}, Eigen::Matrix3d::Zero());
  f.motion_update({0, 0, 0}, {0, 0, 0.5});  // rot1 = 0 (no translation), rot2 = 0.5
  double sy = 0, my = 0, st = 0;
  for (const auto& p : f.particles()) my += p.yaw;
  my /= double(f.particles().size());
  for (const auto& p : f.particles()) {
    sy += (p.yaw - my) * (p.yaw - my);
    st += (p.x - 5) * (p.x - 5) + (p.y - 5) * (p.y - 5);
  }
  sy = std::sqrt(sy / double(f.particles().size()));
  st = std::sqrt(st / double(f.particles().size()));
  EXPECT_NEAR(my, 0.5, 0.01);
  EXPECT_NEAR(sy, std::sqrt(0.1) * 0.5, 0.03 * std::sqrt(0.1) * 0.5);
  EXPECT_NEAR(st, std::sqrt(0.05) * 0.5, 0.03 * std::sqrt(0.05) * 0.5);  // alpha4: translation from rotation
}

// ---- likelihood field ----------------------------------------------------------------------------

TEST(LikelihoodField, DistancesCappedAndOffMap) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  LikelihoodField lf(plan, 0.05, 2.0);
  const double half_diag = 0.05 * std::sqrt(0.5);
  EXPECT_NEAR(lf.distance(10.0, 0.3), 0.3, half_diag + 1e-6);
  EXPECT_NEAR(lf.distance(2.0, 1.0), 1.0, half_diag + 1e-6);
  EXPECT_LE(lf.distance(10.0, 0.0), half_diag + 1e-6);
  EXPECT_DOUBLE_EQ(lf.distance(10.0, 5.0), 2.0);  // 2.7 m from the pillar, 5 m from walls: capped
  EXPECT_DOUBLE_EQ(lf.distance(-50.0, 5.0), 2.0); // off the map
  EXPECT_DOUBLE_EQ(lf.distance(std::nan(""), 5.0), 2.0);
  // Free cells: none on a wall, all inside the bounding box.
  const auto fc = lf.free_cells(0.0);
  EXPECT_GT(fc.size(), 0u);
  for (size_t i = 0; i < fc.size(); i += 97) EXPECT_GT(lf.distance(fc[i].x(), fc[i].y()), half_diag);
}

TEST(Scan, PointsToScanKeepsNearestPerBin) {
  std::vector<Eigen::Vector2d> pts = {{2, 0}, {1.5, 0.001}, {0, 3}, {std::nan(""), 1}, {200, 0}, {-1, -1e-9},
                                      {-1.2, 1e-9}};  // bearing +pi - 1e-9: also the beam at -pi
  int skipped = 0;
  const LaserScan s = points_to_scan(pts, 360, 0.0, 100.0, &skipped);
  EXPECT_EQ(skipped, 2);
  ASSERT_EQ(s.ranges.size(), 360u);
  EXPECT_FLOAT_EQ(s.ranges[180], 1.5f);   // bearing 0 is bin 180 of [-pi, pi)
  EXPECT_FLOAT_EQ(s.ranges[270], 3.0f);   // +90 deg
  EXPECT_FLOAT_EQ(s.ranges[0], 1.0f);     // (-1, -1e-9) is at bearing -pi + 1e-9: the first beam
  int finite_bins = 0;
  for (float r : s.ranges) finite_bins += std::isfinite(r) ? 1 : 0;
  EXPECT_EQ(finite_bins, 3);
}

// ---- the filter on synthetic sequences ----------------------------------------------------------

TEST(Amcl, TracksFromANoisyInitialPoseInTheRoom) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  const auto path = loop_path({{3, 2.5}, {17, 2.5}, {17, 7.5}, {3, 7.5}}, 0.05);  // 38 m at 0.5 m/s, 10 Hz
  Amcl f(plan, Config{});
  // Initial pose 0.3 m / 8 deg off, with the RViz default spread (0.5 m, 15 deg).
  f.init_pose({path[0].x + 0.3, path[0].y - 0.1, path[0].yaw + 8 * kDeg}, diag_cov(0.5, 15 * kDeg));
  fploc::testing::SynthOptions so;
  so.noise_sigma = 0.02;
  so.clutter_fraction = 0.2;
  const RunResult r = drive(f, plan, path, WheelOdometryConfig{}, so);
  EXPECT_GT(r.updates, 100);
  // After the first 2 m: tracking everywhere, and on average within sigma_hit.
  EXPECT_LT(max_from(r.err_xy, 40), kTrackXY);
  EXPECT_LT(max_from(r.err_yaw, 40), kTrackYaw);
  EXPECT_LT(mean_from(r.err_xy, 40), Config{}.sigma_hit);
  // KLD: starts with max_particles, shrinks when the particles agree, never leaves [min, max].
  EXPECT_EQ(r.particles.front(), 2000);
  EXPECT_LT(*std::min_element(r.particles.begin(), r.particles.end()), 2000);
  EXPECT_GE(*std::min_element(r.particles.begin(), r.particles.end()), 500);
  EXPECT_LE(*std::max_element(r.particles.begin(), r.particles.end()), 2000);
}

TEST(Amcl, SelfSimilarCorridorSpreadsAlongTheCorridor) {
  // The corridor ring's long straight walls say nothing about the position along a corridor (only the
  // far end walls do): the filter must stay in the corridor (across: tracking), keep the heading, and its
  // covariance must be larger along the corridor than across it.
  const FloorPlan plan = fploc::testing::corridor_loop();
  const auto path = loop_path({{1, 1}, {23, 1}, {23, 23}, {1, 23}}, 0.08);  // 88 m at 0.8 m/s
  Amcl f(plan, Config{});
  f.init_pose(path[0], diag_cov(0.5, 15 * kDeg));
  fploc::testing::SynthOptions so;
  so.noise_sigma = 0.02;
  so.clutter_fraction = 0.1;
  const RunResult r = drive(f, plan, path, WheelOdometryConfig{}, so);
  double cross_max = 0, along_cov = 0, cross_cov = 0;
  int n = 0;
  for (size_t k = 25; k < r.truth.size(); ++k) {
    const double c = std::abs(std::cos(r.truth[k].yaw)), s = std::abs(std::sin(r.truth[k].yaw));
    if (c > 0.999) {  // along x
      cross_max = std::max(cross_max, std::abs(r.est[k].y - r.truth[k].y));
      along_cov += r.cov[k](0, 0);
      cross_cov += r.cov[k](1, 1);
      ++n;
    } else if (s > 0.999) {
      cross_max = std::max(cross_max, std::abs(r.est[k].x - r.truth[k].x));
      along_cov += r.cov[k](1, 1);
      cross_cov += r.cov[k](0, 0);
      ++n;
    }
  }
  ASSERT_GT(n, 500);
  // Across: never out of the 2 m wide corridor (right after a corner the along-corridor error of the
  // previous corridor becomes the across error of the next one until the side walls pull it back).
  EXPECT_LT(cross_max, 1.0);
  EXPECT_LT(max_from(r.err_yaw, 25), kTrackYaw);
  EXPECT_GT(along_cov, 2 * cross_cov);
  // Along the corridor it drifts but does not jump to another corridor (they are 22 m long).
  EXPECT_LT(max_from(r.err_xy, 25), 3.0);
}

TEST(Amcl, GlobalLocalisationInAnAsymmetricRoom) {
  // No initial pose: max_particles uniform over the free space; the robot drives two laps. Five seeds,
  // each must be tracking on the second lap.
  const FloorPlan plan = l_room();
  const auto path = loop_path({{1, 1}, {8, 1}, {8, 3}, {3, 3}, {3, 7}, {1, 7}}, 0.05, 2);
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    Config c;
    c.seed = seed;
    Amcl f(plan, c);
    f.init_global();
    EXPECT_EQ(f.particles().size(), 2000u);
    EXPECT_GT(f.stats().clusters.size(), 10u);
    fploc::testing::SynthOptions so;
    so.noise_sigma = 0.02;
    so.clutter_fraction = 0.1;
    so.seed = uint32_t(100 * seed);
    const RunResult r = drive(f, plan, path, WheelOdometryConfig{}, so);
    const size_t lap2 = path.size() / 2;
    EXPECT_LT(max_from(r.err_xy, lap2), kTrackXY) << "seed " << seed;
    EXPECT_LT(max_from(r.err_yaw, lap2), kTrackYaw) << "seed " << seed;
    std::cerr << "seed " << seed << ": settled (< " << kTrackXY << " m) after " << settled_at(r.err_xy, kTrackXY)
              << " of " << path.size() << " scans\n";
  }
}

TEST(Amcl, RecoveryAlphasRelocaliseAKidnappedRobot) {
  // One lap tracked from the true pose, then the robot is carried to the middle of the loop (the odometry
  // sees no motion) and does another lap. With nav2's default recovery alphas (0) only the motion noise
  // can move the particles; with the values nav2 documents (slow 0.001, fast 0.1) the likelihood drop
  // brings in random particles, and the filter must settle sooner and within the second lap.
  const FloorPlan plan = l_room();
  const auto lap = loop_path({{1, 1}, {8, 1}, {8, 3}, {3, 3}, {3, 7}, {1, 7}}, 0.05);
  std::vector<Pose2> path = lap, odom = lap;
  const size_t kidnap = path.size(), j = lap.size() / 2;
  for (size_t k = 0; k < lap.size(); ++k) path.push_back(lap[(j + k) % lap.size()]);
  for (size_t k = kidnap; k < path.size(); ++k)
    odom.push_back(compose(odom.back(), k == kidnap ? Pose2{} : between(path[k - 1], path[k])));
  fploc::testing::SynthOptions so;
  so.noise_sigma = 0.02;
  auto run = [&](double slow, double fast) {
    Config c;
    c.recovery_alpha_slow = slow;
    c.recovery_alpha_fast = fast;
    Amcl f(plan, c);
    f.init_pose(path[0], diag_cov(0.1, 2 * kDeg));
    return drive(f, plan, path, WheelOdometryConfig{}, so, &odom);
  };
  const RunResult r0 = run(0, 0), r1 = run(0.001, 0.1);
  // Both track the first lap; the kidnap puts both metres off.
  EXPECT_LT(max_from(std::vector<double>(r0.err_xy.begin(), r0.err_xy.begin() + long(kidnap)), 0), kTrackXY);
  EXPECT_LT(max_from(std::vector<double>(r1.err_xy.begin(), r1.err_xy.begin() + long(kidnap)), 0), kTrackXY);
  EXPECT_GT(r0.err_xy[kidnap], 2.0);
  const size_t s0 = settled_at(r0.err_xy, kTrackXY), s1 = settled_at(r1.err_xy, kTrackXY);
  std::cerr << "kidnapped at scan " << kidnap << " of " << path.size() << "; settled again at " << s0
            << " (no recovery) / " << s1 << " (recovery)\n";
  EXPECT_LT(s1, path.size());
  EXPECT_LT(s1, s0);
}

TEST(Amcl, EstimateModes) {
  // After global initialisation the weighted mean and the best cluster differ; the estimate follows the mode.
  for (EstimateMode m : {EstimateMode::kWeightedMean, EstimateMode::kBestCluster}) {
    Config c;
    c.estimate = m;
    Amcl f(l_room(), c);
    f.init_global();
    ASSERT_GT(f.stats().clusters.size(), 1u);
    const Pose2 want = m == EstimateMode::kWeightedMean ? f.stats().mean : f.stats().clusters[size_t(f.stats().best)].mean;
    EXPECT_DOUBLE_EQ(f.estimate().x, want.x);
    EXPECT_DOUBLE_EQ(f.estimate().y, want.y);
  }
}

// ---- bad input, determinism -----------------------------------------------------------------------

TEST(Amcl, BadScansAreReportedNotFatal) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  Amcl f(plan, Config{});
  f.init_pose({5, 5, 0}, diag_cov(0.2, 5 * kDeg));
  LaserScan empty;
  empty.ranges.assign(360, std::numeric_limits<float>::infinity());
  StepInfo i = f.process({0, 0, 0}, empty);  // first scan: forced update
  EXPECT_TRUE(i.updated);
  EXPECT_FALSE(i.resampled);
  EXPECT_FALSE(i.problem.empty());
  LaserScan nan = empty;
  for (auto& r : nan.ranges) r = std::numeric_limits<float>::quiet_NaN();
  i = f.process({1, 0, 0}, nan);
  EXPECT_EQ(i.beams_used, 0);
  EXPECT_FALSE(i.problem.empty());
  // The prediction still follows the odometry.
  EXPECT_NEAR(f.pose_at({1, 0, 0}).x, 5 + 1, 0.3);
  // Non-finite odometry: refused, nothing changes.
  const auto before = f.particles();
  i = f.process({std::nan(""), 0, 0}, empty);
  EXPECT_FALSE(i.problem.empty());
  EXPECT_FALSE(i.updated);
  ASSERT_EQ(before.size(), f.particles().size());
  EXPECT_EQ(before[7].x, f.particles()[7].x);
  // Mixed NaN / valid beams: only the valid ones count.
  const FeatureFrame fr = fploc::testing::synth_frame(plan, {6, 5, 0}, fploc::testing::SynthOptions{});
  LaserScan s = points_to_scan(points_of(fr), 360, 0.0, 100.0);
  for (size_t k = 1; k < s.ranges.size(); k += 2) s.ranges[k] = std::numeric_limits<float>::quiet_NaN();
  i = f.process({2, 0, 0}, s);
  EXPECT_TRUE(i.updated);
  EXPECT_GT(i.beams_used, 0);
  EXPECT_TRUE(i.problem.empty());
  for (const auto& p : f.particles()) ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.w));
  // Not initialised.
  Amcl g(plan, Config{});
  EXPECT_FALSE(g.process({0, 0, 0}, s).problem.empty());
}

TEST(Amcl, ConfigValidation) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  auto bad = [&](auto mutate) {
    Config c;
    mutate(c);
    EXPECT_THROW(Amcl(plan, c), std::invalid_argument);
  };
  bad([](Config& c) { c.max_particles = 10; });
  bad([](Config& c) { c.alpha3 = -1; });
  bad([](Config& c) { c.sigma_hit = 0; });
  bad([](Config& c) { c.max_beams = 1; });
  bad([](Config& c) { c.resample_interval = 0; });
  bad([](Config& c) { c.recovery_alpha_fast = 2; });
  bad([](Config& c) { c.pf_err = std::nan(""); });
  EXPECT_THROW(Amcl(FloorPlan{}, Config{}), std::runtime_error);
}

TEST(Amcl, DeterministicForASeed) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  const auto path = loop_path({{3, 2.5}, {9, 2.5}, {9, 7.5}}, 0.05);
  auto run = [&](uint64_t seed, Resampler rs) {
    Config c;
    c.seed = seed;
    c.resampler = rs;
    Amcl f(plan, c);
    f.init_pose(path[0], diag_cov(0.5, 15 * kDeg));
    fploc::testing::SynthOptions so;
    so.noise_sigma = 0.02;
    drive(f, plan, path, WheelOdometryConfig{}, so);
    return f.particles();
  };
  for (Resampler rs : {Resampler::kMultinomial, Resampler::kLowVariance}) {
    const auto a = run(1, rs), b = run(1, rs), c = run(2, rs);
    ASSERT_EQ(a.size(), b.size());
    bool same = true;
    for (size_t i = 0; i < a.size(); ++i) same = same && a[i].x == b[i].x && a[i].y == b[i].y && a[i].yaw == b[i].yaw;
    EXPECT_TRUE(same);
    bool differ = a.size() != c.size();
    for (size_t i = 0; !differ && i < a.size(); ++i) differ = a[i].x != c[i].x;
    EXPECT_TRUE(differ);
  }
}

TEST(Amcl, LowVarianceResamplerTracksToo) {
  const FloorPlan plan = fploc::testing::room_with_pillars();
  const auto path = loop_path({{3, 2.5}, {17, 2.5}, {17, 7.5}, {3, 7.5}}, 0.05);
  Config c;
  c.resampler = Resampler::kLowVariance;
  Amcl f(plan, c);
  f.init_pose(path[0], diag_cov(0.5, 15 * kDeg));
  fploc::testing::SynthOptions so;
  so.noise_sigma = 0.02;
  so.clutter_fraction = 0.2;
  const RunResult r = drive(f, plan, path, WheelOdometryConfig{}, so);
  EXPECT_LT(max_from(r.err_xy, 40), kTrackXY);
  EXPECT_LT(mean_from(r.err_xy, 40), Config{}.sigma_hit);
  EXPECT_LT(*std::min_element(r.particles.begin(), r.particles.end()), 2000);
}

// ---- odometry ------------------------------------------------------------------------------------

TEST(WheelOdometry, NoErrorReproducesTheTruth) {
  WheelOdometryConfig c;
  c.scale_error = c.yaw_drift_deg_per_m = c.trans_noise_m_per_sqrt_m = c.yaw_noise_deg_per_sqrt_m = 0;
  WheelOdometrySim w(c);
  const auto path = loop_path({{3, 2.5}, {9, 2.5}, {9, 7.5}}, 0.1);
  w.set_start(path[0]);
  for (const auto& p : path) {
    const Pose2 o = w.update(p);
    EXPECT_NEAR(o.x, p.x, 1e-9);
    EXPECT_NEAR(o.y, p.y, 1e-9);
    EXPECT_NEAR(yaw_err(o.yaw, p.yaw), 0, 1e-9);
  }
}

TEST(WheelOdometry, BiasAndNoiseAsConfigured) {
  // Straight 10 m in 100 steps. Bias only: 10.2 m of odometry path, 10 deg of heading drift.
  WheelOdometryConfig c;
  c.trans_noise_m_per_sqrt_m = c.yaw_noise_deg_per_sqrt_m = 0;
  WheelOdometrySim w(c);
  Pose2 o, prev;
  double len = 0;
  for (int i = 0; i <= 100; ++i) {
    o = w.update({0.1 * i, 0, 0});
    if (i) len += std::hypot(o.x - prev.x, o.y - prev.y);
    prev = o;
  }
  EXPECT_NEAR(len, 10.2, 1e-9);
  EXPECT_NEAR(o.yaw, 10 * kDeg, 1e-9);
  // Noise only: heading std after 10 m = 0.5 deg * sqrt(10); 400 seeds -> sample sd within ~4 % (1 sigma).
  double s2 = 0;
  const int runs = 400;
  for (int s = 0; s < runs; ++s) {
    WheelOdometryConfig n;
    n.scale_error = n.yaw_drift_deg_per_m = 0;
    n.seed = uint64_t(1000 + s);
    WheelOdometrySim x(n);
    Pose2 e;
    for (int i = 0; i <= 100; ++i) e = x.update({0.1 * i, 0, 0});
    s2 += e.yaw * e.yaw;
  }
  EXPECT_NEAR(std::sqrt(s2 / runs), 0.5 * kDeg * std::sqrt(10.0), 0.15 * 0.5 * kDeg * std::sqrt(10.0));
}

TEST(OdometryGuard, JumpsAreRemovedAndReported) {
  OdometryGuard g;
  Pose2 out;
  std::string problem;
  ASSERT_TRUE(g.correct({0, 0, 0}, &out, &problem));
  ASSERT_TRUE(g.correct({0.1, 0, 0}, &out, &problem));
  EXPECT_TRUE(problem.empty());
  ASSERT_TRUE(g.correct({5.1, 3, 2.0}, &out, &problem));  // jump
  EXPECT_FALSE(problem.empty());
  EXPECT_NEAR(out.x, 0.1, 1e-12);
  EXPECT_NEAR(out.y, 0.0, 1e-12);
  EXPECT_NEAR(out.yaw, 0.0, 1e-12);
  problem.clear();
  // After the jump the motion continues from where it was (0.1 m forward in the new raw frame's heading).
  ASSERT_TRUE(g.correct(compose({5.1, 3, 2.0}, {0.1, 0, 0}), &out, &problem));
  EXPECT_TRUE(problem.empty());
  EXPECT_NEAR(out.x, 0.2, 1e-9);
  EXPECT_NEAR(out.y, 0.0, 1e-9);
  EXPECT_EQ(g.jumps(), 1);
  EXPECT_FALSE(g.correct({std::nan(""), 0, 0}, &out, &problem));
  EXPECT_FALSE(problem.empty());
}
