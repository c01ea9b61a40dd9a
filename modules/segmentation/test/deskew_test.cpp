// Gyro de-skew of the sweep's rotation and the gyro bias estimate, on a simulated corridor (the ceiling is
// seen in two short azimuth windows there, so rotation during the 0.1 s sweep tilts the fitted plane most).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"

using namespace fploc;

namespace {

constexpr double kDeg = M_PI / 180.0;

struct SeqResult {
  std::vector<double> tilt_err_deg;  // |roll err| and |pitch err| of every frame with a ceiling
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  int deskewed = 0, frames = 0;
};

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

// Frames [first, first + n) of corridor-loop-fast; gyro fed (plus `added_bias`) when with_gyro.
SeqResult run(bool with_gyro, const Eigen::Vector3d& added_bias, int first = 150, int n = 200) {
  sim::SimulatorOptions o;
  o.scenario = "corridor-loop-fast";
  o.seed = 1;
  o.shared_dir = FPLOC_SHARED_DIR;
  sim::Simulator sim(FloorPlan{}, o);
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  sim::SimScan f;
  SeqResult r;
  double fed = -1e300;
  for (int k = first; k < first + n && k < sim.num_frames(); ++k) {
    if (with_gyro) {
      const double tb = sim.frame_time(k) - o.t0_s + 1.0 / o.rate_hz;
      for (const auto& s : sim.imu())
        if (s.t > fed && s.t < tb) {
          fed = s.t;
          sg.add_gyro(s.gyro + added_bias, int64_t(std::llround((o.t0_s + s.t) * 1e6)));
        }
    }
    sim.frame(k, f);
    const auto& s = sg.process(f.scan);
    ++r.frames;
    r.deskewed += s.deskewed;
    if (!s.ceiling.found) continue;
    // roll/pitch hold at utime + attitude_t (mid-sweep, or the scan's time when the gyro moved them there).
    const Eigen::Vector3d rpy = sim.ground_truth(sim.frame_time(k) + s.attitude_t).rpy();
    r.tilt_err_deg.push_back(std::abs(std::remainder(s.roll - rpy[0], 2 * M_PI)) / kDeg);
    r.tilt_err_deg.push_back(std::abs(std::remainder(s.pitch - rpy[1], 2 * M_PI)) / kDeg);
  }
  r.bias = sg.gyro_bias();
  return r;
}

}  // namespace

TEST(GyroDeskew, CorridorTiltErrorsShrink) {
  const SeqResult raw = run(false, Eigen::Vector3d::Zero());
  const SeqResult desk = run(true, Eigen::Vector3d::Zero());
  ASSERT_EQ(raw.deskewed, 0);
  EXPECT_EQ(desk.deskewed, desk.frames);
  ASSERT_GT(desk.tilt_err_deg.size(), 300u);
  const double raw_p95 = percentile(raw.tilt_err_deg, 0.95), desk_p95 = percentile(desk.tilt_err_deg, 0.95);
  std::cerr << "corridor roll/pitch error p95: " << raw_p95 << " deg as measured, " << desk_p95
            << " deg de-skewed (median " << percentile(raw.tilt_err_deg, 0.5) << " / "
            << percentile(desk.tilt_err_deg, 0.5) << ")\n";
  EXPECT_LT(desk_p95, 0.5 * raw_p95);
  EXPECT_LT(desk_p95, 0.2);
  EXPECT_LT(percentile(desk.tilt_err_deg, 0.5), 0.05);
}

TEST(GyroDeskew, BiasEstimateFollowsAnAddedBias) {
  // The simulated IMU has its own (unknown here) bias; adding a known one must move the estimate by it
  // (the components perpendicular to gravity: the sensor is nearly level, so x and y) and keep the errors.
  const Eigen::Vector3d added(0.01, -0.006, 0.0);  // 0.57 and 0.34 deg/s
  const SeqResult a = run(true, Eigen::Vector3d::Zero());
  const SeqResult b = run(true, added);
  const Eigen::Vector3d moved = b.bias - a.bias;
  std::cerr << "bias estimate " << a.bias.transpose() << " -> " << b.bias.transpose() << " with " << added.transpose()
            << " added\n";
  EXPECT_NEAR(moved.x(), added.x(), 0.0015);
  EXPECT_NEAR(moved.y(), added.y(), 0.0015);
  EXPECT_LT(percentile(b.tilt_err_deg, 0.95), 0.2);
  EXPECT_LT(percentile(b.tilt_err_deg, 0.5), 0.05);
}
