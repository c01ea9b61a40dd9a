// Gyro de-skew of the sweep's rotation and the gyro bias estimate, on a simulated corridor (the ceiling is
// seen in two short azimuth windows there, so rotation during the 0.1 s sweep tilts the fitted plane most).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fploc/core/xyz.h"
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

// The simulator's corridor-loop-fast sequence, seed 1 (its IMU turns fast: the de-skew matters).
sim::SimulatorOptions corridor_fast() {
  sim::SimulatorOptions o;
  o.scenario = "corridor-loop-fast";
  o.seed = 1;
  o.shared_dir = FPLOC_SHARED_DIR;
  return o;
}

// Frames [first, first + n) of corridor-loop-fast; gyro fed (plus `added_bias`) when with_gyro.
SeqResult run(bool with_gyro, const Eigen::Vector3d& added_bias, int first = 150, int n = 200) {
  const sim::SimulatorOptions o = corridor_fast();
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

// The column rotations, integrated block by block with the columns inside a block interpolated (gyro_deskew.cpp),
// against the rotations integrated column by column (each step's midpoint rate): a rate turning about a changing
// axis (1 kHz samples, 1.5 rad/s about z with a 0.5 rad/s wobble), 1024 columns over 0.1 s in whole microseconds.
// Every column within 1e-5 rad and 1e-5 per matrix entry (measured: 4.3e-6 inside the blocks, 3e-8 at their
// ends; 43 um at 10 m in a 95 deg/s turn, against the OS-1's centimetre of range noise).
TEST(GyroDeskew, ColumnRotationsMatchTheExactIntegration) {
  const auto rate = [](double t) {  // rad/s at t [s]
    return Eigen::Vector3d(0.5 * std::sin(20 * t), 0.5 * std::cos(15 * t), 1.5);
  };
  seg::GyroDeskew dk(true);
  const int64_t t0 = 1'000'000;
  // Each sample: the mean rate over the millisecond before it (as the segmenter expects).
  for (int64_t u = t0 - 50'000; u <= t0 + 150'000; u += 1000) {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (int j = 0; j < 10; ++j) m += rate(1e-6 * double(u - 1000 + 100 * j + 50)) / 10;
    dk.add(m, u);
  }
  Scan scan;
  scan.width = 1024;
  scan.height = 1;
  scan.utime = t0;
  scan.column_utime.resize(1024);
  for (int c = 0; c < 1024; ++c) scan.column_utime[size_t(c)] = t0 + (100'000 * c) / 1024;
  ASSERT_TRUE(dk.prepare(scan));
  const int64_t tm = dk.sweep_mid_utime();
  // Column by column: R_c = R_(c-1) exp([w dt]x), w the sample holding the step's midpoint (its interval's mean
  // rate), from the mid-sweep column's rotation on.
  const auto sample_rate = [&](int64_t u) {  // the first sample at or after u
    const int64_t s = t0 - 50'000 + ((u - (t0 - 50'000) + 999) / 1000) * 1000;
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (int j = 0; j < 10; ++j) m += rate(1e-6 * double(s - 1000 + 100 * j + 50)) / 10;
    return m;
  };
  const auto exp_map = [](const Eigen::Vector3d& th) {
    return th.norm() > 0 ? Eigen::Matrix3d(Eigen::AngleAxisd(th.norm(), th.normalized())) : Eigen::Matrix3d::Identity();
  };
  const auto& ct = scan.column_utime;
  int cm = 0;
  while (ct[size_t(cm)] < tm) ++cm;
  std::vector<Eigen::Matrix3d> exact(1024);
  exact[size_t(cm)] = exp_map(sample_rate(tm + (ct[size_t(cm)] - tm) / 2) * (1e-6 * double(ct[size_t(cm)] - tm)));
  for (int c = cm + 1; c < 1024; ++c)
    exact[size_t(c)] = exact[size_t(c - 1)] * exp_map(sample_rate(ct[size_t(c - 1)] + (ct[size_t(c)] - ct[size_t(c - 1)]) / 2) *
                                                      (1e-6 * double(ct[size_t(c)] - ct[size_t(c - 1)])));
  for (int c = cm - 1; c >= 0; --c)
    exact[size_t(c)] = exact[size_t(c + 1)] * exp_map(sample_rate(ct[size_t(c + 1)] + (ct[size_t(c)] - ct[size_t(c + 1)]) / 2) *
                                                      (1e-6 * double(ct[size_t(c)] - ct[size_t(c + 1)])));
  double worst = 0;
  for (int c = 0; c < 1024; ++c) {
    const Eigen::Matrix3d R = dk.rotation_at(c).cast<double>();
    worst = std::max(worst, Eigen::AngleAxisd(R * exact[size_t(c)].transpose()).angle());
    worst = std::max(worst, (R - exact[size_t(c)]).cwiseAbs().maxCoeff());
  }
  std::printf("worst column rotation error %.3g rad\n", worst);
  EXPECT_LT(worst, 1e-5);
}

// The point preparation's de-skewed candidates (the eight-lane pass on AVX2 CPUs, the four-lane one
// elsewhere; both read the rotations in GyroDeskew::interleaved()'s layout) are the returns as measured
// rotated by their column's rotation, each entry ((R_i0 x + R_i1 y) + R_i2 z) in float: bit for bit.
TEST(GyroDeskew, PreparedCandidatesAreTheColumnRotationsApplied) {
  const sim::SimulatorOptions o = corridor_fast();
  sim::Simulator sim(FloorPlan{}, o);
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  seg::GyroDeskew dk(true);
  sim::SimScan f;
  const int k = 160;
  const double tb = sim.frame_time(k) - o.t0_s + 1.0 / o.rate_hz;
  for (const auto& s : sim.imu())
    if (s.t < tb) {
      const int64_t u = int64_t(std::llround((o.t0_s + s.t) * 1e6));
      sg.add_gyro(s.gyro, u);
      dk.add(s.gyro, u);
    }
  sim.frame(k, f);
  const Scan& scan = f.scan;
  ASSERT_TRUE(sg.process(scan).deskewed);
  ASSERT_TRUE(dk.prepare(scan));
  const auto& pts = sg.points();
  const XyzLut lut = make_xyz_lut(scan.beams, scan.width);
  const int W = scan.width;
  size_t checked = 0, differ = 0;
  double largest_rotation = 0;
  for (int u = 0; u < scan.height; ++u)
    for (int c = 0; c < W; ++c) {
      const size_t i = size_t(u) * W + c;
      if (!pts[i].allFinite()) continue;
      const float fr = float(scan.range_mm[i]);
      const float x = lut.direction(i, 0) * fr + lut.offset(i, 0), y = lut.direction(i, 1) * fr + lut.offset(i, 1),
                  z = lut.direction(i, 2) * fr + lut.offset(i, 2);
      const Eigen::Matrix3f R = dk.rotation_at(c);
      largest_rotation = std::max(largest_rotation, double((R - Eigen::Matrix3f::Identity()).cwiseAbs().maxCoeff()));
      for (int r = 0; r < 3; ++r) {
        const float want = (R(r, 0) * x + R(r, 1) * y) + R(r, 2) * z;
        differ += size_t(!(pts[i][r] == want));
      }
      ++checked;
    }
  EXPECT_GT(checked, 30000u);
  EXPECT_GT(largest_rotation, 1e-3);  // (a sweep that turns: the rotations are not the identity)
  EXPECT_EQ(differ, 0u);
}
