// Per-point measurement time (WallPoints::t, FeatureFrame points' t) on simulated OS-1-64 scans, for both
// segmenters. A wall return measured at utime + t by the sensor at its true pose T(utime + t) lies on the
// plan element it hit, so T(utime + t) * p must be on that element. The scans are noise-free and the
// platform moves and turns (room-large-loop-fast): with the right t the points sit on their walls to
// float precision; with t = 0, or the time of the destaggered instead of the measuring (staggered)
// column, they do not (the test checks that it can tell).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fploc/features/features.h"
#include "fploc/floorplan/plan.h"
#include "fploc/segmentation/ransac_segmenter.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"

using namespace fploc;

namespace {

sim::SimulatorOptions options() {
  sim::SimulatorOptions o;
  o.scenario = "room-large-loop-fast";
  o.seed = 2;
  o.range_noise_m = 0.0;
  o.dropout = 0.0;
  o.shared_dir = FPLOC_SHARED_DIR;  // real OS-1-64 beams (and pixel shifts) when ../shared is there
  return o;
}

struct Residuals {
  size_t n = 0;
  double rms = 0, max = 0;       // distance of T(utime + t) p to its element [m]
  double rms_t0 = 0;             // the same with t = 0 (scan start)
  double rms_destaggered = 0;    // with the time of the destaggered column instead of the measuring one
};

// Wall points of `s` that hit a plan wall or pillar in the simulator (per-pixel truth), their distance to
// that element after placing them with the true pose at their measurement time.
Residuals residuals(const seg::Segmentation& s, const sim::Simulator& sim, const sim::SimScan& f) {
  const Scan& sc = f.scan;
  const int W = sc.width;
  const auto& plan = sim.world().plan();
  Residuals r;
  double s2 = 0, s2_0 = 0, s2_d = 0;
  const double t_scan = double(sc.utime) * 1e-6;
  const Eigen::Isometry3d T0 = sim.ground_truth(t_scan).iso();
  for (size_t k = 0; k < s.wall.size(); ++k) {
    const int u = s.wall.ring[k], cd = s.wall.column[k];
    const int shift = sc.beams.pixel_shift_by_row.empty() ? 0 : sc.beams.pixel_shift_by_row[u];
    const int v = ((cd - shift) % W + W) % W;  // measuring (staggered) column
    const size_t i = size_t(u) * W + v;
    const auto label = sim::Label(f.label[i]);
    if (label != sim::Label::kWall && label != sim::Label::kPillar) continue;
    const int32_t e = f.element[i];
    if (e < 0 || size_t(e) >= plan.elements.size()) continue;
    const Eigen::Vector3d p(s.wall.x[k], s.wall.y[k], s.wall.z[k]);
    auto dist = [&](const Eigen::Isometry3d& T) {
      return distance(plan.elements[size_t(e)], Eigen::Vector2d((T * p).head<2>()));
    };
    const double d = dist(sim.ground_truth(t_scan + double(s.wall.t[k])).iso());
    const double d0 = dist(T0);
    const double dd = dist(sim.ground_truth(double(sc.column_utime[size_t(cd)]) * 1e-6).iso());
    s2 += d * d;
    s2_0 += d0 * d0;
    s2_d += dd * dd;
    r.max = std::max(r.max, d);
    ++r.n;
  }
  if (r.n) {
    r.rms = std::sqrt(s2 / r.n);
    r.rms_t0 = std::sqrt(s2_0 / r.n);
    r.rms_destaggered = std::sqrt(s2_d / r.n);
  }
  return r;
}

void feed_imu(const sim::Simulator& sim, int k, seg::Segmenter& sg) {
  const double t0 = sim.frame_time(k) - sim.options().t0_s, t1 = t0 + 1.0 / sim.options().rate_hz;
  for (const auto& smp : sim.imu())
    if (smp.t >= t0 - 0.02 && smp.t < t1 + 0.005)
      sg.add_gyro(smp.gyro, int64_t(std::llround((sim.options().t0_s + smp.t) * 1e6)));
}

// Frames of the sequence where the platform moves fast (largest residuals at t = 0).
void run(seg::Segmenter& sg, bool with_imu) {
  sim::Simulator sim(FloorPlan{}, options());
  feat::FeatureExtractor fx;
  sim::SimScan f;
  double worst_rms = 0, worst_max = 0, min_t0 = 1e9, min_destaggered = 1e9, max_t = 0;
  int checked = 0, deskewed = 0;
  for (int k = 40; k < sim.num_frames() && checked < 12; k += 37) {
    if (with_imu) feed_imu(sim, k, sg);
    sim.frame(k, f);
    const auto& s = sg.process(f.scan);
    ASSERT_NE(s.status, seg::SegStatus::kBadInput) << s.status_text;
    ASSERT_EQ(s.wall.t.size(), s.wall.size());
    for (float t : s.wall.t) {
      ASSERT_GE(t, 0.f);
      ASSERT_LT(t, 0.1f);  // within the 10 Hz sweep
      max_t = std::max(max_t, double(t));
    }
    const Residuals r = residuals(s, sim, f);
    if (r.n < 1000) continue;  // no ceiling known yet (no wall points) or a sparse frame
    ++checked;
    deskewed += s.deskewed;
    worst_rms = std::max(worst_rms, r.rms);
    worst_max = std::max(worst_max, r.max);
    min_t0 = std::min(min_t0, r.rms_t0);
    min_destaggered = std::min(min_destaggered, r.rms_destaggered);

    // Features carry the time of the wall point they came from.
    const auto& ft = fx.process(s);
    ASSERT_EQ(fx.source().size(), ft.size());
    for (size_t j = 0; j < ft.size(); ++j) ASSERT_EQ(ft.points[j].t, s.wall.t[size_t(fx.source()[j])]);
  }
  ASSERT_GE(checked, 6);
  EXPECT_GT(max_t, 0.09);  // times cover the sweep
  if (with_imu) { EXPECT_EQ(deskewed, checked) << "gyro de-skew should be active"; }
  // Right times: on the walls to the range quantisation (1 mm steps: |error| <= 0.5 mm along the ray,
  // rms 0.29 mm) plus float rounding.
  EXPECT_LT(worst_rms, 0.0005);
  EXPECT_LT(worst_max, 0.0015);
  // The test can tell: scan-start time and destaggered-column time leave the points off their walls.
  EXPECT_GT(min_t0, 5 * worst_rms);
  bool shifted = false;
  for (int sh : f.scan.beams.pixel_shift_by_row) shifted |= sh != 0;
  if (shifted) EXPECT_GT(min_destaggered, 2 * worst_rms);
  else std::cerr << "beams without pixel shifts (no ../shared data): destaggered-time check not possible\n";
  std::cerr << sg.name() << (with_imu ? " (gyro de-skew)" : "") << ": " << checked << " frames, rms "
            << worst_rms * 1e3 << " mm (max " << worst_max * 1e3 << " mm) with t; >= " << min_t0 * 1e3
            << " mm with t = 0; >= " << min_destaggered * 1e3 << " mm with destaggered-column times\n";
}

}  // namespace

TEST(PointTime, RingSegmenterWallPointsAndFeatures) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  run(sg, false);
}

TEST(PointTime, RingSegmenterWithGyroDeskewPublishesRawPointsAndTimes) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  run(sg, true);
}

TEST(PointTime, RansacSegmenterWallPointsAndFeatures) {
  seg::RansacSegmenter sg(seg::SegmenterConfig{});
  run(sg, false);
}
