// fploc map validate: the paper's Table III (per depth: leaf length, hit by 1st, hit by 1st or 2nd,
// ns per query) over uniform samples in the plan's bounding box, ground truth by brute force, plus
// exact-mode rows and the baselines (brute force, KD-tree over sampled points, distance grid).
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>

#include "fploc/annf/ablation.h"
#include "fploc/annf/annf.h"
#include "fploc/annf/baselines.h"
#include "fploc/core/text_out.h"
#include "map_tool.h"

using nlohmann::json;

namespace fploc {
namespace {

// A hit: the returned element is at the true nearest distance (ties and duplicate elements count).
constexpr double kTol = 1e-9;

// Thread CPU time: the machine is shared, wall time would count other processes' slices.
double now_ns() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e9 + double(ts.tv_nsec);
}

template <typename F>
double time_per_query(const std::vector<Eigen::Vector2d>& pts, size_t n, F&& f) {
  n = std::min(n, pts.size());
  volatile double sink = 0;
  double acc = 0;
  const double t0 = now_ns();
  for (size_t i = 0; i < n; ++i) acc += f(pts[i]);
  const double t1 = now_ns();
  sink = acc;
  (void)sink;
  return (t1 - t0) / double(n);
}

const std::map<int, std::array<double, 3>> kPaper = {{3, {61.61, 76.10, 0.24}}, {4, {76.08, 87.85, 0.16}},
                                                     {5, {86.29, 93.61, 0.24}}, {6, {91.96, 96.24, 0.18}},
                                                     {7, {94.90, 97.28, 0.25}}, {8, {96.46, 98.84, 0.35}}};

}  // namespace

int cmd_validate(const FloorPlan& plan, const ValidateArgs& a, bool as_json) {
  int d0 = 0, d1 = 0;
  if (std::sscanf(a.depths.c_str(), "%d-%d", &d0, &d1) != 2) {
    if (std::sscanf(a.depths.c_str(), "%d", &d0) != 1) throw std::runtime_error("--depths: expected A-B, e.g. 3-8");
    d1 = d0;
  }
  if (d0 < 1 || d1 < d0 || d1 > 16) throw std::runtime_error("--depths: expected 1 <= A <= B <= 16");
  if (a.samples < 1) throw std::runtime_error("--samples must be >= 1");
  Box2 bb = plan.bounds();
  if (a.sample_area == "fields") {  // the area covered by the root fields (extends past the plan)
    annf::AnnfOptions ro;
    ro.root_length = a.root;
    ro.margin = a.margin;
    ro.max_depth = 1;
    bb = annf::Annf::build(plan, ro).covered();
  } else if (a.sample_area != "bbox") {
    throw std::runtime_error("--sample-area: bbox or fields");
  }
  std::mt19937_64 rng(a.seed);
  std::uniform_real_distribution<double> ux(bb.min.x(), bb.max.x()), uy(bb.min.y(), bb.max.y());
  std::vector<Eigen::Vector2d> pts(size_t(a.samples));
  for (auto& p : pts) p = {ux(rng), uy(rng)};

  std::cerr << "fploc map validate: " << plan.elements.size() << " elements, " << pts.size()
            << " uniform samples in " << bb.size().x() << " x " << bb.size().y() << " m; brute-force ground truth...\n";
  std::vector<double> truth(pts.size());
  std::vector<int> truth_id(pts.size());
  const double tb0 = now_ns();
  for (size_t i = 0; i < pts.size(); ++i) truth_id[i] = nearest_element_brute_force(plan, pts[i], &truth[i]);
  const double brute_ns = (now_ns() - tb0) / double(pts.size());

  json rows = json::array();
  struct Config {
    annf::AnnfMode mode;
    annf::PaperRule rule;
    bool distinct;
  };
  std::vector<Config> configs;
  if (a.mode != "exact") {
    if (a.all_rules) {
      for (bool distinct : {false, true})
        for (annf::PaperRule r : {annf::PaperRule::kChildLeaf, annf::PaperRule::kUndoOnly, annf::PaperRule::kChildLeafOrdered, annf::PaperRule::kFull,
                            annf::PaperRule::kCollapseFirst, annf::PaperRule::kCollapsePair})
          configs.push_back({annf::AnnfMode::kPaper, r, distinct});
    } else {
      configs.push_back({annf::AnnfMode::kPaper, annf::parse_paper_rule(a.rule), a.distinct});
    }
  }
  if (a.mode != "paper") configs.push_back({annf::AnnfMode::kExact, annf::PaperRule::kChildLeaf, false});
  const size_t timed = std::min<size_t>(pts.size(), 2000000);
  const bool by_id = a.hit_by == "id";

  std::fprintf(stderr, "%-6s %-44s %5s %9s %8s %8s %8s %8s %8s %10s %9s | paper: %6s %6s\n", "mode", "rule", "depth",
               "leaf[cm]", "hit1", "hit1|2", "exact", "ns/q", "batch", "bytes", "build[ms]", "hit1", "hit1|2");
  for (const auto& [mode, rule, distinct] : configs) {
    for (int depth = d0; depth <= d1; ++depth) {
      annf::AnnfOptions o;
      o.mode = mode;
      o.paper_rule = rule;
      o.root_length = a.root;
      o.margin = a.margin;
      o.max_depth = depth + (mode == annf::AnnfMode::kExact ? a.exact_depth : 0);
      o.exact_max_candidates = a.max_candidates;
      o.exact_refine_levels = a.refine;
      o.paper_distinct_distances = distinct;
      o.paper_candidates = a.candidates == "passing"           ? annf::AnnfOptions::Candidates::kPassingElseAll
                           : a.candidates == "passing-inherit" ? annf::AnnfOptions::Candidates::kPassingInherit
                                                               : annf::AnnfOptions::Candidates::kAll;
      const double t0 = now_ns();
      const annf::Annf f = annf::Annf::build(plan, o);
      const double build_ms = (now_ns() - t0) / 1e6;
      size_t h1 = 0, h12 = 0, hx = 0;
      for (size_t i = 0; i < pts.size(); ++i) {
        int n;
        const uint32_t* c = f.lookup(pts[i], &n);
        const double t = truth[i] + kTol;
        auto hit = [&](uint32_t id) {
          return by_id ? int(id) == truth_id[i] : distance(plan.elements[id], pts[i]) <= t;
        };
        if (c && n >= 1 && hit(c[0])) {
          ++h1;
          ++h12;
        } else if (c && n >= 2 && hit(c[1])) {
          ++h12;
        }
        // Exact hit: the returned element is at the true nearest distance and the returned
        // distance is that distance.
        double d;
        const int id = f.nearest(pts[i], &d);
        hx += id >= 0 && distance(plan.elements[id], pts[i]) <= t && std::abs(d - truth[i]) <= kTol;
      }
      const double ns = time_per_query(pts, timed, [&](const Eigen::Vector2d& p) {
        double d;
        return f.nearest(p, &d) + d;
      });
      // A scan's worth of points at a time through nearest_batch().
      double batch_ns = 0;
      {
        const size_t B = 1024, nb = std::min(timed, pts.size());
        std::vector<int> bi(B);
        std::vector<double> bd(B);
        volatile double sink = 0;
        const double t0 = now_ns();
        for (size_t off = 0; off < nb; off += B) {
          const size_t m = std::min(B, nb - off);
          f.nearest_batch(pts.data() + off, m, bi.data(), bd.data());
          sink = sink + bd[0];
        }
        batch_ns = (now_ns() - t0) / double(nb);
      }
      const double lookup_ns = time_per_query(pts, timed, [&](const Eigen::Vector2d& p) {
        int n;
        const uint32_t* c = f.lookup(p, &n);
        return c ? double(c[0] + n) : 0.0;
      });
      const annf::AnnfStats s = f.stats();
      const double N = double(pts.size());
      json row = {{"mode", to_string(mode)},
                  {"rule", mode == annf::AnnfMode::kPaper ? to_string(rule) : "-"},
                  {"distinct_distances", distinct},
                  {"candidates", mode == annf::AnnfMode::kPaper ? a.candidates : "-"},
                  {"depth", o.max_depth},
                  {"leaf_length_m", f.leaf_length()},
                  {"hit_first", h1 / N},
                  {"hit_first_or_second", h12 / N},
                  {"hit_exact", hx / N},
                  {"exact_misses", pts.size() - hx},
                  {"ns_per_query", ns},
                  {"batch_ns_per_query", batch_ns},
                  {"lookup_ns", lookup_ns},
                  {"tree_bytes", s.file_bytes},
                  {"bytes", s.bytes},
                  {"nodes", s.nodes},
                  {"leaves", s.leaves},
                  {"mean_candidates", s.mean_leaf_candidates},
                  {"max_candidates", s.max_leaf_candidates},
                  {"build_ms", build_ms}};
      auto it = kPaper.find(o.max_depth);
      if (mode == annf::AnnfMode::kPaper && it != kPaper.end()) {
        row["paper_hit_first"] = it->second[0] / 100;
        row["paper_hit_first_or_second"] = it->second[1] / 100;
      }
      rows.push_back(row);
      const std::string rname = mode == annf::AnnfMode::kPaper ? std::string(to_string(rule)) + (distinct ? "+distinct" : "") +
                                                               (a.candidates != "all" ? "+" + a.candidates : "")
                                                         : "-";
      std::fprintf(stderr, "%-6s %-44s %5d %9.2f %7.2f%% %7.2f%% %7.3f%% %8.2f %8.2f %10zu %9.0f", to_string(mode),
                   rname.c_str(), o.max_depth, f.leaf_length() * 100, 100 * h1 / N,
                   100 * h12 / N, 100 * hx / N, ns, batch_ns, s.bytes, build_ms);
      if (mode == annf::AnnfMode::kPaper && it != kPaper.end())
        std::fprintf(stderr, " | paper: %5.2f%% %5.2f%%\n", it->second[0], it->second[1]);
      else
        std::fprintf(stderr, "\n");
    }
  }

  json out = {{"elements", plan.elements.size()}, {"samples", pts.size()}, {"rows", rows}};
  out["sample_box_m"] = {bb.min.x(), bb.min.y(), bb.max.x(), bb.max.y()};
  out["sample_area"] = a.sample_area;
  json base = {{"brute_force_ns", brute_ns}};
  if (!a.no_baselines) {
    const double spacing = a.root / double(1u << (a.baseline_depth - 1));
    const annf::SampledKdTree kd(plan, spacing);
    size_t kh = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      const int id = kd.nearest(pts[i]);
      kh += distance(plan.elements[id], pts[i]) <= truth[i] + kTol;
    }
    const double kd_ns = time_per_query(pts, timed, [&](const Eigen::Vector2d& p) {
      double d;
      return kd.nearest(p, &d) + d;
    });
    annf::AnnfOptions xo;
    xo.mode = annf::AnnfMode::kExact;
    xo.root_length = a.root;
    xo.margin = a.margin;
    xo.max_depth = a.baseline_depth + 2;
    const annf::Annf ex = annf::Annf::build(plan, xo);
    const annf::DistanceGrid grid(ex, spacing);
    size_t gh = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      const int id = grid.read(pts[i]);
      gh += id >= 0 && distance(plan.elements[id], pts[i]) <= truth[i] + kTol;
    }
    const double grid_ns = time_per_query(pts, timed, [&](const Eigen::Vector2d& p) {
      float d = 0;
      return grid.read(p, &d) + double(d);
    });
    base["kdtree_ns"] = kd_ns;
    base["kdtree_hit"] = kh / double(pts.size());
    base["kdtree_points"] = kd.points();
    base["kdtree_bytes"] = kd.bytes();
    base["kdtree_spacing_m"] = spacing;
    base["grid_ns"] = grid_ns;
    base["grid_hit"] = gh / double(pts.size());
    base["grid_bytes"] = grid.bytes();
    base["grid_resolution_m"] = spacing;
    std::fprintf(stderr,
                 "baselines: brute force %.1f ns/q; KD-tree (%zu points every %.2f cm) %.1f ns/q, hit %.2f%%, %zu B; "
                 "distance grid (%.2f cm) %.2f ns/q, hit %.2f%%, %zu B\n",
                 brute_ns, kd.points(), spacing * 100, kd_ns, 100.0 * kh / double(pts.size()), kd.bytes(), spacing * 100,
                 grid_ns, 100.0 * gh / double(pts.size()), grid.bytes());
  } else {
    std::fprintf(stderr, "baselines: brute force %.1f ns/q\n", brute_ns);
  }
  out["baselines"] = base;
  if (as_json) std::cout << fploc::json_text(out, 1) << "\n";
  return 0;
}

}  // namespace fploc
