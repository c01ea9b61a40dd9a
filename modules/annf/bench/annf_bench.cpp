// Look-up speed on SIST-F4 (walls + columns): ANNF (paper / exact) vs distance grid, KD-tree over
// sampled points, brute force. Random points in the bounding box and points near walls (as a scan
// gives). Every ANNF look-up includes the distance to the returned element.
//   build-annf/bin/annf_bench [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>

#include "fploc/annf/annf.h"
#include "fploc/annf/baselines.h"
#include "fploc/floorplan/io.h"

using namespace fploc;
using namespace fploc::annf;

namespace {

struct Fixture {
  FloorPlan plan;
  std::unique_ptr<Annf> paper, exact;
  std::unique_ptr<DistanceGrid> grid;
  std::unique_ptr<SampledKdTree> kd;
  std::vector<Eigen::Vector2d> random_pts, wall_pts;
  bool ok = false;
};

Fixture& fixture() {
  static Fixture f = [] {
    Fixture f;
    const std::string path = std::string(FPLOC_SHARED_DIR) + "/data/floorplans/shanghaitech_SIST-F4-filtered.dxf";
    if (!std::filesystem::exists(path)) return f;
    PlanLoadOptions o;
    o.layer_globs = {"*WALL*", "*COLS*"};
    o.quiet = true;
    f.plan = load_floor_plan(path, o);
    // FPLOC_INDEX_CELLS: size of the dense top-level index (speed/memory trade-off).
    const uint32_t cells = std::getenv("FPLOC_INDEX_CELLS") ? uint32_t(std::atol(std::getenv("FPLOC_INDEX_CELLS"))) : 0;
    AnnfOptions po;
    po.index_cells = cells;
    po.max_depth = 7;
    f.paper = std::make_unique<Annf>(Annf::build(f.plan, po));
    AnnfOptions xo;
    xo.mode = AnnfMode::kExact;
    // FPLOC_EXACT_DEPTH / FPLOC_EXACT_MC / FPLOC_EXACT_REFINE: exact-mode depth, leaf candidate
    // threshold and candidate refinement levels.
    xo.max_depth = std::getenv("FPLOC_EXACT_DEPTH") ? std::atoi(std::getenv("FPLOC_EXACT_DEPTH")) : 8;
    xo.exact_max_candidates = std::getenv("FPLOC_EXACT_MC") ? std::atoi(std::getenv("FPLOC_EXACT_MC")) : 2;
    xo.exact_refine_levels = std::getenv("FPLOC_EXACT_REFINE") ? std::atoi(std::getenv("FPLOC_EXACT_REFINE")) : 2;
    xo.index_cells = cells;
    f.exact = std::make_unique<Annf>(Annf::build(f.plan, xo));
    const double res = 6.0 / 64;  // the leaf length at depth 7 (9.375 cm)
    f.grid = std::make_unique<DistanceGrid>(*f.exact, res);
    f.kd = std::make_unique<SampledKdTree>(f.plan, res);
    std::mt19937_64 rng(42);
    const Box2 b = f.plan.bounds();
    std::uniform_real_distribution<double> ux(b.min.x(), b.max.x()), uy(b.min.y(), b.max.y()), u01(0, 1);
    std::normal_distribution<double> noise(0, 0.05);
    std::uniform_int_distribution<size_t> pick(0, f.plan.elements.size() - 1);
    const size_t n = 1 << 18;
    for (size_t i = 0; i < n; ++i) f.random_pts.push_back({ux(rng), uy(rng)});
    for (size_t i = 0; i < n; ++i) {
      const Element& e = f.plan.elements[pick(rng)];
      Eigen::Vector2d p;
      if (e.kind == ElementKind::kSegment) {
        p = e.a + (e.b - e.a) * u01(rng);
      } else {
        const double t = e.a0 + (e.a1 - e.a0) * u01(rng);
        p = e.c + e.r * Eigen::Vector2d(std::cos(t), std::sin(t));
      }
      f.wall_pts.push_back(p + Eigen::Vector2d(noise(rng), noise(rng)));
    }
    f.ok = true;
    return f;
  }();
  return f;
}

const std::vector<Eigen::Vector2d>& points(Fixture& f, int near_wall) { return near_wall ? f.wall_pts : f.random_pts; }

template <typename F>
void run(benchmark::State& st, F&& fn) {
  Fixture& f = fixture();
  if (!f.ok) {
    st.SkipWithError("no ../shared/data");
    return;
  }
  const auto& pts = points(f, int(st.range(0)));
  const size_t mask = pts.size() - 1;
  size_t i = 0;
  double acc = 0;
  for (auto _ : st) {
    acc += fn(f, pts[i]);
    i = (i + 1) & mask;
  }
  benchmark::DoNotOptimize(acc);
  st.SetItemsProcessed(int64_t(st.iterations()));
}

void BM_AnnfPaper(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    double d;
    return f.paper->nearest(p, &d) + d;
  });
  st.counters["bytes"] = double(fixture().ok ? fixture().paper->stats().bytes : 0);
}
void BM_AnnfExact(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    double d;
    return f.exact->nearest(p, &d) + d;
  });
  st.counters["bytes"] = double(fixture().ok ? fixture().exact->stats().bytes : 0);
}
// Batch look-ups of 1024 points (a scan), with software prefetching; time per point.
void batch(benchmark::State& st, const Annf& a) {
  Fixture& f = fixture();
  auto pts = points(f, int(st.range(0)));
  // FPLOC_BENCH_POINTS: use only the first N points (N small: everything cache-resident).
  if (std::getenv("FPLOC_BENCH_POINTS")) pts.resize(size_t(std::atol(std::getenv("FPLOC_BENCH_POINTS"))));
  const size_t B = 1024;
  std::vector<int> ids(B);
  std::vector<double> d(B);
  size_t off = 0;
  for (auto _ : st) {
    a.nearest_batch(pts.data() + off, B, ids.data(), d.data());
    benchmark::DoNotOptimize(d.data());
    off = (off + B) & (pts.size() - 1);
  }
  st.SetItemsProcessed(int64_t(st.iterations() * B));
}
void BM_AnnfPaperBatch(benchmark::State& st) {
  if (!fixture().ok) return st.SkipWithError("no ../shared/data");
  batch(st, *fixture().paper);
}
void BM_AnnfExactBatch(benchmark::State& st) {
  if (!fixture().ok) return st.SkipWithError("no ../shared/data");
  batch(st, *fixture().exact);
}
// lookup_batch(): candidate ids of 1024 points at a time, no distance.
void lookup_batch(benchmark::State& st, const Annf& a) {
  Fixture& f = fixture();
  auto pts = points(f, int(st.range(0)));
  if (std::getenv("FPLOC_BENCH_POINTS")) pts.resize(size_t(std::atol(std::getenv("FPLOC_BENCH_POINTS"))));
  const size_t B = 1024;
  std::vector<const uint32_t*> ids(B);
  std::vector<int> n(B);
  size_t off = 0;
  for (auto _ : st) {
    a.lookup_batch(pts.data() + off, B, ids.data(), n.data());
    benchmark::DoNotOptimize(ids.data());
    off = (off + B) & (pts.size() - 1);
  }
  st.SetItemsProcessed(int64_t(st.iterations() * B));
}
void BM_AnnfPaperLookupBatch(benchmark::State& st) {
  if (!fixture().ok) return st.SkipWithError("no ../shared/data");
  lookup_batch(st, *fixture().paper);
}
void BM_AnnfExactLookupBatch(benchmark::State& st) {
  if (!fixture().ok) return st.SkipWithError("no ../shared/data");
  lookup_batch(st, *fixture().exact);
}
void BM_AnnfExactLookupOnly(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    int n;
    const uint32_t* c = f.exact->lookup(p, &n);
    return c ? double(c[0] + n) : 0.0;
  });
}
void BM_AnnfPaperLookupOnly(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    int n;
    const uint32_t* c = f.paper->lookup(p, &n);
    return c ? double(c[0] + n) : 0.0;
  });
}
void BM_DistanceGrid(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    float d = 0;
    return f.grid->read(p, &d) + double(d);
  });
  st.counters["bytes"] = double(fixture().ok ? fixture().grid->bytes() : 0);
}
void BM_KdTree(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    double d;
    return f.kd->nearest(p, &d) + d;
  });
  st.counters["bytes"] = double(fixture().ok ? fixture().kd->bytes() : 0);
}
void BM_BruteForce(benchmark::State& st) {
  run(st, [](Fixture& f, const Eigen::Vector2d& p) {
    double d;
    return nearest_element_brute_force(f.plan, p, &d) + d;
  });
}

}  // namespace

// Arg 0: random points in the bounding box; 1: points within ~5 cm of walls/columns.
BENCHMARK(BM_AnnfPaper)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfExact)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfPaperBatch)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfExactBatch)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfPaperLookupBatch)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfExactLookupBatch)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfExactLookupOnly)->Arg(0)->Arg(1);
BENCHMARK(BM_AnnfPaperLookupOnly)->Arg(0)->Arg(1);
BENCHMARK(BM_DistanceGrid)->Arg(0)->Arg(1);
BENCHMARK(BM_KdTree)->Arg(0)->Arg(1);
BENCHMARK(BM_BruteForce)->Arg(0)->Arg(1);
BENCHMARK_MAIN();
