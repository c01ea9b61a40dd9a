// The feature extractor alone on fixed segmentations (issue 14 item 7): simulated OS-1-64 scans of a room
// and a corridor (real beam angles from ../shared when present) are segmented once before any timing.
//   build/bin/features_bench                       Google Benchmark, CPU time per scan: BM_Features cycles
//                                                  through the 48 inputs (cold caches), BM_FeaturesFreshInput
//                                                  copies each input just before (warm, as in the pipeline)
//   build/bin/features_bench --hash                FNV-1a hash of every feature of every scan (x, y bits,
//                                                  kind, group, t, source index, status, group count):
//                                                  "optimised without changing results" for the features
//                                                  alone, whatever the segmenter does
#include <benchmark/benchmark.h>

#include <cstring>
#include <iostream>

#include "fploc/features/features.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"

namespace {
using namespace fploc;

const std::vector<seg::Segmentation>& segmentations() {
  static const std::vector<seg::Segmentation> segs = [] {
    std::vector<seg::Segmentation> out;
    for (const char* scenario : {"room-small-loop-medium", "corridor-loop-medium", "room-large-loop-fast"}) {
      sim::SimulatorOptions o;
      o.scenario = scenario;
      o.shared_dir = FPLOC_SHARED_DIR;
      sim::Simulator sim(FloorPlan{}, o);
      seg::RingSegmenter sg(seg::SegmenterConfig{});
      sim::SimScan s;
      int taken = 0;
      for (int k = 0; k < sim.num_frames() && taken < 16; k += 7, ++taken) {
        sim.frame(k, s);
        out.push_back(sg.process(s.scan));
      }
    }
    return out;
  }();
  return segs;
}

void BM_Features(benchmark::State& st) {
  const auto& segs = segmentations();
  feat::FeatureExtractor fx;
  size_t k = 0;
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(segs[k++ % segs.size()]).size());
}
BENCHMARK(BM_Features)->Unit(benchmark::kMicrosecond);

// The input fresh in the cache, as after the segmenter that wrote it (BM_SegmenterPlusFeatures of
// perception_ratio_bench): each scan's wall points are copied into the input before the (timed) extraction.
void BM_FeaturesFreshInput(benchmark::State& st) {
  const auto& segs = segmentations();
  feat::FeatureExtractor fx;
  seg::Segmentation in;
  size_t k = 0;
  for (auto _ : st) {
    st.PauseTiming();
    in = segs[k++ % segs.size()];
    st.ResumeTiming();
    benchmark::DoNotOptimize(fx.process(in).size());
  }
}
BENCHMARK(BM_FeaturesFreshInput)->Unit(benchmark::kMicrosecond);

int hash() {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* p, size_t bytes) {
    for (size_t i = 0; i < bytes; ++i) h = (h ^ static_cast<const uint8_t*>(p)[i]) * 1099511628211ull;
  };
  feat::FeatureExtractor fx;
  size_t features = 0, groups = 0;
  for (const auto& s : segmentations()) {
    const auto& f = fx.process(s);
    mix(&f.status, sizeof f.status);
    mix(&f.num_groups, sizeof f.num_groups);
    for (size_t i = 0; i < f.size(); ++i) {
      const auto& p = f.points[i];
      const float x = float(p.p.x()), y = float(p.p.y());
      mix(&x, sizeof x);
      mix(&y, sizeof y);
      mix(&p.kind, sizeof p.kind);
      mix(&p.group, sizeof p.group);
      mix(&p.t, sizeof p.t);
      mix(&fx.source()[i], sizeof(int32_t));
    }
    features += f.size();
    groups += size_t(f.num_groups);
  }
  std::cout << segmentations().size() << " segmentations, " << features << " features, " << groups
            << " groups, features hash " << std::hex << h << std::dec << "\n";
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--hash") == 0) return hash();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
