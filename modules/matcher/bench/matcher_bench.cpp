// Single-frame registration per scan for each correspondence look-up (synthetic room, 360 features
// with 2 cm noise and 20 % clutter, guess 10 cm / 2 degrees off as from the motion model), and the
// raw cost of one candidate query.
#include <benchmark/benchmark.h>

#include <random>

#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/matcher/plan_terms.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::matcher;

static void BM_RegisterFrame(benchmark::State& st, std::string lookup) {
  auto map = make_localization_map(fploc::testing::room_with_pillars(), lookup);
  fploc::testing::SynthOptions so;
  so.noise_sigma = 0.02;
  so.clutter_fraction = 0.2;
  const Pose2 truth{10, 5, 0.7};
  const FeatureFrame f = fploc::testing::synth_frame(*map.plan, truth, so);
  MatcherConfig cfg;
  cfg.max_correspondence_m = cfg.gate_tracking_m;  // as while tracking (Matcher::process)
  double err = 0;
  int iters = 0;
  for (auto _ : st) {
    MatchResult r = register_frame(*map.lookup, f, {truth.x + 0.1, truth.y - 0.05, truth.yaw + 0.035}, cfg);
    err = std::hypot(r.pose.x - truth.x, r.pose.y - truth.y);
    iters = r.iterations;
    benchmark::DoNotOptimize(r);
  }
  st.counters["err_m"] = err;
  st.counters["iterations"] = iters;
  st.counters["points"] = double(f.points.size());
}

static void BM_Candidates(benchmark::State& st, std::string lookup) {
  auto map = make_localization_map(fploc::testing::room_with_pillars(), lookup);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(0, 20), uy(0, 10);
  std::vector<Eigen::Vector2d> pts(4096);
  for (auto& p : pts) p = {ux(rng), uy(rng)};
  size_t i = 0;
  int cand[kMaxCandidates];
  for (auto _ : st) {
    benchmark::DoNotOptimize(map.lookup->candidates(pts[i++ & 4095], cand, kMaxCandidates));
  }
}

BENCHMARK_CAPTURE(BM_RegisterFrame, annf_exact, std::string("annf-exact"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_RegisterFrame, annf_paper, std::string("annf-paper"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_RegisterFrame, annf_paper_first, std::string("annf-paper-first"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_RegisterFrame, kdtree, std::string("kdtree"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_RegisterFrame, brute_force, std::string("brute-force"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Candidates, annf_exact, std::string("annf-exact"));
BENCHMARK_CAPTURE(BM_Candidates, annf_paper, std::string("annf-paper"));
BENCHMARK_CAPTURE(BM_Candidates, kdtree, std::string("kdtree"));
BENCHMARK_CAPTURE(BM_Candidates, brute_force, std::string("brute-force"));

BENCHMARK_MAIN();
