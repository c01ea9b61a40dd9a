// Windowed optimisation cost per frame (synthetic room, 0.6 m/s at 10 Hz, 360 beams with 2 cm noise,
// keyframe every 0.1 m: most frames are keyframes, each triggers a W-keyframe solve).
#include <benchmark/benchmark.h>

#include <cmath>

#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/optimizer/window.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::optimizer;

static void BM_WindowPerFrame(benchmark::State& st) {
  auto map = matcher::make_localization_map(fploc::testing::room_with_pillars(), "annf-exact");
  std::vector<FrameInput> frames;
  matcher::Matcher m(*map.lookup, {});
  auto truth = [](double t) { return Pose2{3.0 + 0.6 * t, 3.0 + 1.5 * std::sin(0.25 * t), 0.1 * t}; };
  m.set_pose(truth(0));
  for (int k = 0; k < 100; ++k) {
    fploc::testing::SynthOptions so;
    so.noise_sigma = 0.02;
    so.seed = uint32_t(k + 1);
    FrameInput in;
    in.features = fploc::testing::synth_frame(*map.plan, truth(0.1 * k), so, int64_t(k) * 100000);
    const matcher::MatchResult r = m.process(in.features);
    in.sfr = r.pose;
    in.status = r.status;
    frames.push_back(in);
  }
  OptimizerConfig cfg;
  cfg.window = int(st.range(0));
  int64_t n = 0;
  for (auto _ : st) {
    WindowOptimizer opt(*map.lookup, cfg);
    std::vector<PoseOut> finals;
    for (const auto& f : frames) benchmark::DoNotOptimize(opt.add(f, &finals));
    opt.flush(&finals);
    n += int64_t(frames.size());
  }
  st.SetItemsProcessed(n);
  st.counters["us_per_frame"] = benchmark::Counter(double(n), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_WindowPerFrame)->Arg(1)->Arg(5)->Arg(10)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
