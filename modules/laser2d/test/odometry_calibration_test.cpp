// Online wheel-odometry calibration from fitted increments: recovers a yaw bias per metre, a turn scale error
// and a translation scale from noisy pairs; ignores a pair that is not the wheels' error (a wrong fit); forgets
// an old bias over the distance travelled (default configuration unless said).
#include "fploc/laser2d/odometry_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using fploc::Pose2;
namespace l2 = fploc::laser2d;
constexpr double kDeg = M_PI / 180;

struct Wheels {
  double b = 0, k = 0, c = 1;  // the true errors: fitted = odometry with these applied
};

// One random step: (odometry increment, fitted increment with 1 cm / 0.3 deg of fit noise).
std::pair<Pose2, Pose2> pair_of(const Wheels& w, std::mt19937& rng) {
  std::uniform_real_distribution<double> step(0.1, 1.5), turn(-40 * kDeg, 40 * kDeg);
  std::normal_distribution<double> nxy(0, 0.01), nyaw(0, 0.3 * kDeg);
  const double s = step(rng), t = turn(rng);
  const Pose2 odo{s * std::cos(t / 2), s * std::sin(t / 2), t};
  const double T = t + w.b * s + w.k * t;
  const Pose2 fit{w.c * s * std::cos(T / 2) + nxy(rng), w.c * s * std::sin(T / 2) + nxy(rng), T + nyaw(rng)};
  return {odo, fit};
}

TEST(OdometryCalibration, RecoversBiasTurnScaleAndScale) {
  const Wheels w{3.5 * kDeg, -0.04, 0.965};  // intel's wheels
  // Long memory: 200 pairs outweigh the ridge (which shrinks the estimate by ~2 % for b, ~10 % for k here).
  l2::OdometryCalibrationConfig cfg;
  cfg.memory_m = 1e4;
  l2::OdometryCalibration cal(cfg);
  std::mt19937 rng(1);
  for (int i = 0; i < 200; ++i) {
    const auto [o, f] = pair_of(w, rng);
    EXPECT_TRUE(cal.observe(o, f));
  }
  EXPECT_NEAR(cal.bias_rad_per_m(), w.b, 0.3 * kDeg);
  EXPECT_NEAR(cal.turn_scale_error(), w.k, 0.01);
  EXPECT_NEAR(cal.scale(), w.c, 0.005);
  // The corrected increment of a new step is the true one to the fit noise.
  const Pose2 o{1.0, 0.0, 0.0}, c = cal.correct(o);
  EXPECT_NEAR(c.yaw, w.b, 0.3 * kDeg);
  EXPECT_NEAR(std::hypot(c.x, c.y), w.c, 0.005);
}

TEST(OdometryCalibration, IgnoresAPairThatIsNotTheWheels) {
  const Wheels w{2 * kDeg, 0, 1};
  l2::OdometryCalibration cal;
  std::mt19937 rng(2);
  for (int i = 0; i < 40; ++i) {
    const auto [o, f] = pair_of(w, rng);
    cal.observe(o, f);
  }
  const double b = cal.bias_rad_per_m();
  // A fit that locked 30 degrees away on a 1 m step.
  EXPECT_FALSE(cal.observe({1, 0, 0}, {1, 0, 30 * kDeg}));
  EXPECT_DOUBLE_EQ(cal.bias_rad_per_m(), b);
  // Untrained: the raw odometry (the ridge holds it at zero correction).
  const l2::OdometryCalibration fresh;
  const Pose2 c = fresh.correct({1, 0.1, 0.2});
  EXPECT_NEAR(c.x, 1, 1e-12);
  EXPECT_NEAR(c.y, 0.1, 1e-12);
  EXPECT_NEAR(c.yaw, 0.2, 1e-12);
}

TEST(OdometryCalibration, ForgetsAnOldBiasOverDistance) {
  l2::OdometryCalibration cal;
  std::mt19937 rng(3);
  for (int i = 0; i < 80; ++i) {
    const auto [o, f] = pair_of({3 * kDeg, 0, 1}, rng);
    cal.observe(o, f);
  }
  // With the default 30 m memory the ridge keeps ~15 % of the estimate at zero.
  EXPECT_NEAR(cal.bias_rad_per_m(), 3 * kDeg, 0.6 * kDeg);
  // The floor changes: -1 deg/m from here (changes of a few degrees per metre pass the outlier test).
  double travelled = 0;
  while (travelled < 100) {
    const auto [o, f] = pair_of({-1 * kDeg, 0, 1}, rng);
    cal.observe(o, f);
    travelled += std::hypot(o.x, o.y);
  }
  EXPECT_NEAR(cal.bias_rad_per_m(), -1 * kDeg, 0.5 * kDeg);
}

}  // namespace
