// AMCL speed: one filter update (motion + likelihood field + KLD resampling) with nav2's defaults on
// the synthetic room, for the particle counts nav2 moves between (500 tracking, 2000 at start), and the
// likelihood-field set-up (once per plan).
#include <benchmark/benchmark.h>

#include "fploc/amcl/amcl.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::amcl;

namespace {

LaserScan scan_at(const FloorPlan& plan, const Pose2& p) {
  testing::SynthOptions so;
  so.noise_sigma = 0.02;
  so.clutter_fraction = 0.2;
  const FeatureFrame f = testing::synth_frame(plan, p, so);
  std::vector<Eigen::Vector2d> pts;
  for (const auto& q : f.points) pts.push_back(q.p);
  return points_to_scan(pts, 360, 0.0, 100.0);
}

void BM_Update(benchmark::State& st) {
  const FloorPlan plan = testing::room_with_pillars();
  Config c;
  c.min_particles = c.max_particles = int(st.range(0));
  Amcl f(plan, c);
  f.init_pose({5, 5, 0}, Eigen::Vector3d(0.25, 0.25, 0.07).asDiagonal());
  const LaserScan s = scan_at(plan, {5, 5, 0});
  Pose2 odom{0, 0, 0};
  f.process(odom, s);
  for (auto _ : st) {
    odom.x += 0.3;  // > update_min_d: every call is a full update
    f.process(odom, s);
    odom.x -= 0.3;
    f.process(odom, s);
  }
  st.SetItemsProcessed(st.iterations() * 2);
  st.counters["particles"] = double(f.particles().size());
}
BENCHMARK(BM_Update)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime();

void BM_SensorUpdateOnly(benchmark::State& st) {
  const FloorPlan plan = testing::room_with_pillars();
  Config c;
  c.min_particles = c.max_particles = int(st.range(0));
  Amcl f(plan, c);
  f.init_pose({5, 5, 0}, Eigen::Vector3d(0.25, 0.25, 0.07).asDiagonal());
  const LaserScan s = scan_at(plan, {5, 5, 0});
  for (auto _ : st) benchmark::DoNotOptimize(f.sensor_update(s));
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_SensorUpdateOnly)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime();

void BM_NoUpdateScan(benchmark::State& st) {
  // The common case: the robot moved less than update_min_d / update_min_a since the last update.
  const FloorPlan plan = testing::room_with_pillars();
  Amcl f(plan, Config{});
  f.init_pose({5, 5, 0}, Eigen::Vector3d(0.25, 0.25, 0.07).asDiagonal());
  const LaserScan s = scan_at(plan, {5, 5, 0});
  f.process({0, 0, 0}, s);
  for (auto _ : st) benchmark::DoNotOptimize(f.process({0.01, 0, 0}, s));
}
BENCHMARK(BM_NoUpdateScan)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime();

void BM_FieldSetup(benchmark::State& st) {
  const FloorPlan plan = testing::room_with_pillars();
  for (auto _ : st) {
    LikelihoodField lf(plan, 0.05, 2.0);
    benchmark::DoNotOptimize(lf.distance(1, 1));
  }
}
BENCHMARK(BM_FieldSetup)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

}  // namespace

BENCHMARK_MAIN();
