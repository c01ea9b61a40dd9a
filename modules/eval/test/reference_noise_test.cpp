#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "fploc/eval/reference_noise.h"

using namespace fploc;
using namespace fploc::eval;

namespace {

// A wandering planar path: 0.3 m steps, slowly turning.
std::vector<Pose2> truth(int n) {
  std::vector<Pose2> t;
  Pose2 p;
  for (int i = 0; i < n; ++i) {
    t.push_back(p);
    p = compose(p, {0.3, 0.0, 0.05 * std::sin(0.01 * i)});
  }
  return t;
}

// The truth with white noise: sigma_axis in x and y, sigma_yaw in yaw; time stamps 0.1 s apart (+ jitter below the
// association's window).
Trajectory noisy(const std::vector<Pose2>& t, double sigma_axis, double sigma_yaw, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd;
  Trajectory out;
  for (size_t i = 0; i < t.size(); ++i) {
    const double time = 0.1 * double(i) + 0.002 * nd(rng) * 0.1;
    out.push_back(StampedPose::from_rpy(time, Eigen::Vector3d(t[i].x + sigma_axis * nd(rng), t[i].y + sigma_axis * nd(rng), 0),
                                        0, 0, t[i].yaw + sigma_yaw * nd(rng)));
  }
  return out;
}

}  // namespace

// Three copies of one path with known, different white noise: each source's per-pose sigma comes back (horizontal:
// sqrt(2) x the per-axis sigma), at lag 1 and lag 3 alike (white noise), whichever order they are passed in.
TEST(ReferenceNoise, ThreeCorneredHatRecoversEachSourcesWhiteNoise) {
  const auto t = truth(20000);
  const Trajectory a = noisy(t, 0.01, 0.002, 1), b = noisy(t, 0.03, 0.004, 2), c = noisy(t, 0.05, 0.001, 3);
  for (int lag : {1, 3}) {
    const HatResult r = three_cornered_hat(a, b, c, 0.02, lag);
    EXPECT_EQ(r.increments, t.size() - size_t(lag));
    // The yaw noise also turns each increment (0.3 m x a few mrad), a few per cent of the position's.
    EXPECT_NEAR(r.ref.pose_sigma_xy_m, std::sqrt(2.0) * 0.01, 0.003 + 0.3 * 0.002 * lag) << lag;
    EXPECT_NEAR(r.est.pose_sigma_xy_m, std::sqrt(2.0) * 0.03, 0.003 + 0.3 * 0.004 * lag) << lag;
    EXPECT_NEAR(r.third.pose_sigma_xy_m, std::sqrt(2.0) * 0.05, 0.003) << lag;
    EXPECT_NEAR(r.ref.pose_sigma_yaw_rad, 0.002, 0.0002) << lag;
    EXPECT_NEAR(r.est.pose_sigma_yaw_rad, 0.004, 0.0002) << lag;
    EXPECT_NEAR(r.third.pose_sigma_yaw_rad, 0.001, 0.0002) << lag;
  }
  const HatResult swapped = three_cornered_hat(c, a, b);
  EXPECT_NEAR(swapped.ref.pose_sigma_xy_m, std::sqrt(2.0) * 0.05, 0.003);
  EXPECT_NEAR(swapped.est.pose_sigma_xy_m, std::sqrt(2.0) * 0.01, 0.003);
}

// A random walk (drift) is not white: its increment variance grows with the lag, while a white source's does not.
TEST(ReferenceNoise, DriftGrowsWithTheLagWhiteNoiseDoesNot) {
  const auto t = truth(20000);
  std::mt19937 rng(7);
  std::normal_distribution<double> nd;
  std::vector<Pose2> walk = t;
  double ox = 0, oy = 0;
  for (auto& p : walk) {
    ox += 0.01 * nd(rng), oy += 0.01 * nd(rng);
    p.x += ox, p.y += oy;
  }
  const Trajectory ref = noisy(t, 0.02, 0, 4), est = noisy(t, 0.02, 0, 5), drift = noisy(walk, 0, 0, 6);
  const HatResult r1 = three_cornered_hat(ref, est, drift, 0.02, 1), r4 = three_cornered_hat(ref, est, drift, 0.02, 4);
  EXPECT_NEAR(r1.third.increment_var_xy_m2, 2 * 0.01 * 0.01, 0.3 * 2 * 0.01 * 0.01);
  EXPECT_NEAR(r4.third.increment_var_xy_m2, 4 * r1.third.increment_var_xy_m2, 0.3 * 4 * r1.third.increment_var_xy_m2);
  EXPECT_NEAR(r4.ref.pose_sigma_xy_m, r1.ref.pose_sigma_xy_m, 0.004);
}

// Trajectories that do not overlap in time: one clear error, not a division by zero.
TEST(ReferenceNoise, TooFewCommonIncrementsIsAnError) {
  const auto t = truth(50);
  Trajectory a = noisy(t, 0.01, 0, 1), b = noisy(t, 0.01, 0, 2), c = noisy(t, 0.01, 0, 3);
  for (auto& p : c) p.t += 100;
  EXPECT_THROW(three_cornered_hat(a, b, c), std::invalid_argument);
  EXPECT_THROW(three_cornered_hat(a, b, b, 0.02, 0), std::invalid_argument);
  EXPECT_DOUBLE_EQ(signed_sqrt(-4), -2);
}

// The estimate and the third trajectory need not share the reference's poses or clock: every 7th estimate pose
// dropped (an unreliable pose left out), the estimate stamped 0.55 s late (eval's --offset takes it back), and
// the third trajectory at twice the rate and starting later. The increments are those where all three have both
// poses, and each source's sigma still comes back.
TEST(ReferenceNoise, AssociatesByTimeWithGapsOffsetsAndOtherRates) {
  const auto t = truth(20000);
  const Trajectory ref = noisy(t, 0.01, 0.002, 1);
  const Trajectory est = noisy(t, 0.03, 0.004, 2);
  Trajectory gapped;  // every 7th pose dropped, the rest stamped 0.55 s late
  for (size_t i = 0; i < est.size(); ++i)
    if (i % 7 != 3) {
      StampedPose q = est[i];
      q.t += 0.55;
      gapped.push_back(q);
    }
  std::vector<Pose2> fine;  // the truth at twice the rate: the path's poses and midpoints between them
  for (size_t i = 0; i + 1 < t.size(); ++i) {
    fine.push_back(t[i]);
    fine.push_back(compose(t[i], {0.15, 0.0, 0.0}));
  }
  Trajectory third;
  for (const auto& p : noisy(fine, 0.05, 0.001, 3)) {
    StampedPose q = p;
    q.t /= 2;  // 0.05 s apart: on the reference's times every other pose
    if (q.t >= 100) third.push_back(q);
  }
  const HatResult r = three_cornered_hat(ref, gapped, third, 0.02, 1, -0.55);
  // Reference increments (i, i + 1) from t = 100 s where neither end is a dropped estimate pose.
  size_t expect = 0;
  for (size_t i = 1000; i + 1 < t.size() - 1; ++i) expect += (i % 7 != 3) && ((i + 1) % 7 != 3);
  EXPECT_NEAR(double(r.increments), double(expect), 2);
  EXPECT_NEAR(r.ref.pose_sigma_xy_m, std::sqrt(2.0) * 0.01, 0.003 + 0.3 * 0.002);
  EXPECT_NEAR(r.est.pose_sigma_xy_m, std::sqrt(2.0) * 0.03, 0.003 + 0.3 * 0.004);
  EXPECT_NEAR(r.third.pose_sigma_xy_m, std::sqrt(2.0) * 0.05, 0.003);
  // Without the offset the estimate matches nothing.
  EXPECT_THROW(three_cornered_hat(ref, gapped, third, 0.02, 1, 0), std::invalid_argument);
}

// A difference that is constant (here a stationary third trajectory against a straight constant-speed reference, and
// an estimate offset from the reference) has variance 0. The one-pass sum-of-squares formula left a rounding
// residue of either sign, and `fploc eval --hat` said "gt xy not resolvable (negative variance estimate)" for -1.7e-9 m.
TEST(ReferenceNoise, AConstantDifferenceIsZeroNotARoundingResidue) {
  Trajectory ref, est, third;
  for (int i = 0; i < 50; ++i) {
    const double t = 0.1 * i;
    ref.push_back(StampedPose::from_rpy(t, Eigen::Vector3d(0.1 * i, 0, 0), 0, 0, 0));
    est.push_back(StampedPose::from_rpy(t, Eigen::Vector3d(0.1 * i + 0.3, 0.2, 0), 0, 0, 0));
    third.push_back(StampedPose::from_rpy(t, Eigen::Vector3d(5, 5, 0), 0, 0, 0.4));
  }
  const HatResult h = three_cornered_hat(ref, est, third);
  for (const HatSource* s : {&h.ref, &h.est, &h.third}) {
    EXPECT_EQ(s->increment_var_xy_m2, 0.0);
    EXPECT_EQ(s->increment_var_yaw_rad2, 0.0);
    EXPECT_EQ(s->pose_sigma_xy_m, 0.0);
  }
}

// Coordinates far too large (1e200: another unit, a corrupt file) overflow the differences' squares: no source's xy
// variance can be separated, all three are NaN (not a finite value of either sign); yaw is still estimated.
TEST(ReferenceNoise, OverflowingDifferencesAreNaN) {
  const auto t = truth(60);
  const Trajectory ref = noisy(t, 0.01, 0.002, 1), est = noisy(t, 0.02, 0.002, 2);
  Trajectory third = noisy(t, 0.01, 0.002, 3);
  for (size_t i = 0; i < third.size(); ++i) third[i].p.x() = i % 2 ? 1e200 : -1e200;
  const HatResult h = three_cornered_hat(ref, est, third);
  for (const HatSource* s : {&h.ref, &h.est, &h.third}) {
    EXPECT_TRUE(std::isnan(s->increment_var_xy_m2)) << s->increment_var_xy_m2;
    EXPECT_TRUE(std::isnan(s->pose_sigma_xy_m));
    EXPECT_TRUE(std::isfinite(s->increment_var_yaw_rad2));
  }
}
