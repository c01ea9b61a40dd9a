// Global relocalization speed: whole-plan search (no guess) and a 3 m disc around a lost pose, on the
// synthetic room (20 x 10 m) and the corridor ring (24 x 24 m); 360 features with noise and clutter.
#include <benchmark/benchmark.h>

#include "fploc/matcher/map.h"
#include "fploc/relocalization/relocalizer.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::reloc;
namespace synth = fploc::testing;

static void run(benchmark::State& state, FloorPlan plan, Pose2 truth, bool region) {
  auto map = matcher::make_localization_map(std::move(plan), "annf-exact");
  Relocalizer reloc(*map.plan, *map.lookup);
  synth::SynthOptions o;
  o.noise_sigma = 0.02;
  o.clutter_fraction = 0.2;
  const FeatureFrame f = synth::synth_frame(*map.plan, truth, o);
  std::optional<SearchRegion> r;
  if (region) r = SearchRegion{{truth.x + 1.5, truth.y - 1.0, truth.yaw + 0.8}, 3.0, M_PI};
  int64_t hyps = 0, found = 0;
  for (auto _ : state) {
    const RelocResult res = reloc.locate(f, r);
    hyps = res.hypotheses;
    found += res.status == RelocStatus::kFound;
  }
  state.counters["hypotheses"] = double(hyps);
  state.counters["found"] = double(found) / double(state.iterations());
}

static void BM_RoomWholePlan(benchmark::State& s) { run(s, synth::room_with_pillars(), {10, 7, 2.0}, false); }
static void BM_RoomRegion(benchmark::State& s) { run(s, synth::room_with_pillars(), {10, 7, 2.0}, true); }
static void BM_CorridorWholePlan(benchmark::State& s) { run(s, synth::corridor_loop(), {1, 12, 1.5}, false); }
BENCHMARK(BM_RoomWholePlan)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RoomRegion)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CorridorWholePlan)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
