// Simulated frames: labels agree with the geometry, noise/dropout statistics, determinism per seed.
#include <gtest/gtest.h>

#include <cmath>

#include "fploc/core/xyz.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using namespace fploc::sim;

namespace {

SimulatorOptions quiet_opts(const std::string& scenario, uint64_t seed) {
  SimulatorOptions o;
  o.scenario = scenario;
  o.seed = seed;
  o.shared_dir = FPLOC_SHARED_DIR;
  return o;
}

}  // namespace

TEST(Sensor, LabelsMatchGeometry) {
  SimulatorOptions o = quiet_opts("room-large-loop-fast", 3);
  o.range_noise_m = 0;
  o.dropout = 0;
  Simulator sim(FloorPlan{}, o);
  ASSERT_GE(sim.world().furniture().size(), 1u);
  SimScan f;
  const int k = sim.num_frames() / 3;  // moving
  sim.frame(k, f);
  std::vector<Eigen::Vector3f> pts;
  scan_to_xyz(f.scan, sim.lidar().lut(), pts);
  const FloorPlan& plan = sim.world().plan();
  int counts[kNumLabels] = {0};
  const int W = f.scan.width;
  for (int u = 0; u < f.scan.height; ++u)
    for (int v = 0; v < W; ++v) {
      const size_t i = size_t(u) * W + v;
      const Label l = Label(f.label[i]);
      ++counts[int(l)];
      if (f.scan.range_mm[i] == 0) {
        EXPECT_EQ(l, Label::kNone);
        continue;
      }
      // World point through the pose at the column's own time (motion during the sweep).
      const Eigen::Isometry3d T = sim.ground_truth(f.scan.column_utime[size_t(v)] * 1e-6).iso();
      const Eigen::Vector3d p = T * pts[i].cast<double>();
      const double tol = 0.004;  // mm rounding + float LUT + µs timestamp rounding
      switch (l) {
        case Label::kFloor: EXPECT_NEAR(p.z(), 0.0, tol); break;
        case Label::kCeiling: {
          const double c = sim.world().ceiling_at(p.x(), p.y());
          ASSERT_FALSE(std::isnan(c));
          EXPECT_NEAR(p.z(), c, tol);
          break;
        }
        case Label::kWall:
        case Label::kPillar: {
          ASSERT_GE(f.element[i], 0);
          const Element& e = plan.elements[size_t(f.element[i])];
          EXPECT_NEAR(distance(e, p.head<2>()), 0.0, tol);
          EXPECT_EQ(l == Label::kPillar, e.kind == ElementKind::kCircle);
          break;
        }
        case Label::kClutter: EXPECT_GE(f.element[i], 0); break;
        default: ADD_FAILURE() << "return without label";
      }
    }
  EXPECT_GT(counts[int(Label::kFloor)], 2000);
  EXPECT_GT(counts[int(Label::kCeiling)], 2000);
  EXPECT_GT(counts[int(Label::kWall)], 5000);
}

TEST(Sensor, NoiseAndDropout) {
  SimulatorOptions o = quiet_opts("room-small-loop-medium", 1);
  o.range_noise_m = 0.02;
  o.dropout = 0.05;
  Simulator sim(FloorPlan{}, o);
  SimScan f;
  sim.frame(10, f);
  double s2 = 0, mean = 0;
  int n = 0, hit = 0, dropped = 0;
  for (size_t i = 0; i < f.scan.range_mm.size(); ++i) {
    if (f.true_range_m[i] <= 0.5) continue;
    ++hit;
    if (f.scan.range_mm[i] == 0) {
      ++dropped;
      continue;
    }
    const double e = f.scan.range_mm[i] * 1e-3 - f.true_range_m[i];
    mean += e;
    s2 += e * e;
    ++n;
  }
  mean /= n;
  const double sd = std::sqrt(s2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.001);
  EXPECT_NEAR(sd, 0.02, 0.002);
  const double drop = double(dropped) / hit;
  EXPECT_GT(drop, 0.045);  // dropout plus grazing-angle losses
  EXPECT_LT(drop, 0.15);
}

TEST(Sensor, DeterministicPerSeed) {
  auto run = [](uint64_t seed) {
    Simulator sim(FloorPlan{}, quiet_opts("corridor-loop-fast", seed));
    SimScan f;
    sim.frame(25, f);
    return std::make_pair(f.scan.range_mm, sim.imu()[500].accel);
  };
  const auto a = run(7), b = run(7), c = run(8);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
  EXPECT_NE(a.first, c.first);
  EXPECT_NE(a.second, c.second);
}

TEST(Sensor, BeamsFromSharedMetadataOrNominal) {
  std::string src;
  const BeamIntrinsics b = default_beams(FPLOC_SHARED_DIR, &src);
  EXPECT_EQ(b.beams(), 64);
  EXPECT_EQ(b.pixel_shift_by_row.size(), 64u);
  const BeamIntrinsics n = nominal_os1_64();
  // Real and nominal patterns agree to within a degree (the nominal one is a fallback, not a guess).
  for (int u = 0; u < 64; ++u) {
    EXPECT_NEAR(b.altitude_deg[size_t(u)], n.altitude_deg[size_t(u)], 1.0) << u;
    EXPECT_NEAR(b.azimuth_deg[size_t(u)], n.azimuth_deg[size_t(u)], 0.5) << u;
  }
  std::string err;
  BeamIntrinsics x;
  EXPECT_FALSE(load_beam_intrinsics_json("/nonexistent.json", x, &err));
  EXPECT_NE(err.find("/nonexistent.json"), std::string::npos);
}
