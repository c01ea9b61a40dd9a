// Ray-casting speed of the simulator: one OS-1-64 1024x10 frame (65,536 rays, per-column poses, noise).
// Real time needs < 100 ms per frame on one core.
#include <benchmark/benchmark.h>

#include "fploc/sim/simulator.h"

using namespace fploc::sim;

static void run(benchmark::State& state, const char* scenario) {
  SimulatorOptions o;
  o.scenario = scenario;
  o.shared_dir = FPLOC_SHARED_DIR;
  Simulator sim(fploc::FloorPlan{}, o);
  SimScan f;
  int k = 0;
  for (auto _ : state) {
    sim.frame(k, f);
    k = (k + 7) % sim.num_frames();
    benchmark::DoNotOptimize(f.scan.range_mm.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(double(state.iterations()) * 65536, benchmark::Counter::kIsRate);
  state.counters["realtime_factor"] =
      benchmark::Counter(double(state.iterations()) * 0.1, benchmark::Counter::kIsRate);
}

static void BM_FrameRoomFast(benchmark::State& s) { run(s, "room-large-loop-fast"); }
static void BM_FrameCorridorFast(benchmark::State& s) { run(s, "corridor-loop-fast"); }
BENCHMARK(BM_FrameRoomFast)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FrameCorridorFast)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
