// Per-scan cost of the perception front end on a 64 x 1024 (65,536-point) OS-1-like scan of a furnished
// room: the paper's segmenter, the feature extractor, both together, and the PCL RANSAC segmenter.
#include <benchmark/benchmark.h>

#include "fploc/features/features.h"
#include "fploc/segmentation/ransac_segmenter.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"

namespace {
using namespace fploc;

const seg::synth::SynthScan& scan() {
  static const auto s = [] {
    seg::synth::SensorPose pose{-1.0, 0.5, 1.45, 1.0 * M_PI / 180, -0.8 * M_PI / 180, 0.4};
    return seg::synth::render(seg::synth::furnished_room(), pose, seg::synth::os1_like_beams(64), 1024, 0.02, 0.01, 3);
  }();
  return s;
}

void BM_RingSegmenter(benchmark::State& st) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  sg.process(scan().scan);  // warm: LUT, previous plane (steady state of a sequence)
  for (auto _ : st) benchmark::DoNotOptimize(sg.process(scan().scan).wall.size());
  st.counters["wall_points"] = double(sg.last().wall.size());
}
BENCHMARK(BM_RingSegmenter)->Unit(benchmark::kMicrosecond);

void BM_Features(benchmark::State& st) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  const seg::Segmentation s = sg.process(scan().scan);
  feat::FeatureExtractor fx;
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(s).size());
  st.counters["features"] = double(fx.process(s).size());
}
BENCHMARK(BM_Features)->Unit(benchmark::kMicrosecond);

void BM_SegmenterPlusFeatures(benchmark::State& st) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  sg.process(scan().scan);
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(sg.process(scan().scan)).size());
}
BENCHMARK(BM_SegmenterPlusFeatures)->Unit(benchmark::kMicrosecond);

void BM_RansacSegmenter(benchmark::State& st) {
  seg::RansacSegmenter sg(seg::SegmenterConfig{});
  sg.process(scan().scan);
  for (auto _ : st) benchmark::DoNotOptimize(sg.process(scan().scan).wall.size());
}
BENCHMARK(BM_RansacSegmenter)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
