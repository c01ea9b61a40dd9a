// fploc map build|validate|render|export-pgm  (contracts in docs/DESIGN.md)
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "fploc/core/text_out.h"
#include "fploc/runtime/cli_messages.h"
#include "fploc/runtime/cli_numbers.h"
#include "fploc/annf/ablation.h"
#include "fploc/annf/annf.h"
#include "fploc/annf/baselines.h"
#include "fploc/floorplan/io.h"
#include "map_tool.h"

using nlohmann::json;
using namespace fploc;

namespace {

struct PlanArgs {
  std::string plan, layers, units, floor;
  double cut_height = 1.0;
  void add(CLI::App* app, const std::string& prefix = "") {
    const std::string p = "--" + prefix;
    app->add_option(p + "plan", plan, "floor plan (.dxf, .csv, .json, .fpmap), building (.pbtxt) or IFC (.ifc)")->required();
    app->add_option(p + "floor", floor, "building/IFC: the floor (storey) to use (default: the first)");
    app->add_option(p + "ifc-cut-height", cut_height, "IFC: cut walls, columns, ... this many metres above each storey's floor (default 1)");
    app->add_option(p + "layers", layers, "layer globs, comma-separated (e.g. '*WALL*,*COLS*')");
    app->add_option(p + "units", units, "drawing units override: m, cm, mm, in, ft");
  }
  FloorPlan load() const {
    PlanLoadOptions o;
    std::stringstream ss(layers);
    std::string g;
    while (std::getline(ss, g, ','))
      if (!g.empty()) o.layer_globs.push_back(g);
    o.units_override = units;
    o.floor = floor;
    o.ifc_cut_height = cut_height;
    return load_floor_plan(plan, o);
  }
};

struct AnnfArgs {
  std::string mode = "paper", rule = "child-leaf-ordered";
  int depth = 7, max_candidates = 2, refine = 2;
  bool distinct = true;
  std::string candidates = "passing";
  double root = 6.0, margin = 2.0;
  void add(CLI::App* app, bool with_depth = true) {
    app->add_option("--mode", mode, "paper | exact")->check(CLI::IsMember({"paper", "exact"}));
    if (with_depth) app->add_option("--depth", depth, "maximum depth (1 = root fields only)");
    app->add_option("--root", root, "root field length in metres (default 6)");
    app->add_option("--margin", margin, "metres of field around the plan's bounding box (default 2)");
    app->add_option("--rule", rule, "paper stopping rule: child-leaf | undo-only | child-leaf-ordered | full | collapse-first | collapse-pair");
    app->add_option("--max-candidates", max_candidates, "exact mode: subdivide while a leaf has more candidates (default 2)");
    app->add_option("--refine", refine, "exact mode: candidate refinement levels (default 2, 0 = simple bound)");
    app->add_flag("--distinct,!--no-distinct", distinct, "paper mode: two nearest at distinct distances (default on)");
    app->add_option("--candidates", candidates, "paper mode: all | passing (default) | passing-inherit")
        ->check(CLI::IsMember({"all", "passing", "passing-inherit"}));
  }
  annf::AnnfOptions options() const {
    annf::AnnfOptions o;
    o.mode = annf::parse_annf_mode(mode);
    o.paper_rule = annf::parse_paper_rule(rule);
    o.max_depth = depth;
    o.root_length = root;
    o.exact_max_candidates = max_candidates;
    o.exact_refine_levels = refine;
    o.paper_distinct_distances = distinct;
    o.paper_candidates = candidates == "passing"           ? annf::AnnfOptions::Candidates::kPassingElseAll
                         : candidates == "passing-inherit" ? annf::AnnfOptions::Candidates::kPassingInherit
                                                           : annf::AnnfOptions::Candidates::kAll;
    o.margin = margin;
    return o;
  }
};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

json stats_json(const annf::Annf& a, double build_ms) {
  const annf::AnnfStats s = a.stats();
  return {{"mode", to_string(a.options().mode)},
          {"rule", to_string(a.options().paper_rule)},
          {"distinct_distances", a.options().paper_distinct_distances},
          {"candidates", a.options().paper_candidates == annf::AnnfOptions::Candidates::kAll             ? "all"
                         : a.options().paper_candidates == annf::AnnfOptions::Candidates::kPassingInherit ? "passing-inherit"
                                                                                                     : "passing"},
          {"exact_max_candidates", a.options().exact_max_candidates},
          {"exact_refine_levels", a.options().exact_refine_levels},
          {"tree_bytes", a.stats().file_bytes},
          {"depth", a.options().max_depth},
          {"root_length_m", a.options().root_length},
          {"leaf_length_m", a.leaf_length()},
          {"elements", a.plan().elements.size()},
          {"nodes", s.nodes},
          {"leaves", s.leaves},
          {"bytes", s.bytes},
          {"mean_candidates", s.mean_leaf_candidates},
          {"max_candidates", s.max_leaf_candidates},
          {"deepest", s.deepest},
          {"build_ms", build_ms}};
}

int cmd_build(const PlanArgs& pa, const AnnfArgs& aa, const std::string& out, bool as_json) {
  const FloorPlan plan = pa.load();
  const auto t0 = std::chrono::steady_clock::now();
  const annf::Annf a = annf::Annf::build(plan, aa.options());
  const double ms = ms_since(t0);
  a.save(out);
  json j = stats_json(a, ms);
  j["out"] = out;
  j["file_bytes"] = std::filesystem::file_size(out);
  std::cerr << "fploc map build: " << plan.elements.size() << " elements, mode " << aa.mode << ", depth " << aa.depth
            << ", leaf " << a.leaf_length() << " m, " << j["leaves"] << " leaves, " << j["bytes"] << " bytes, "
            << ms << " ms -> " << out << "\n";
  if (as_json) std::cout << fploc::json_text(j, 1) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc map: floor plans and the ANNF"};
  fploc::rt::install_cli_messages(app, "fploc map");
  app.require_subcommand(1);
  // `fploc map diff` is its own program (fploc-map-diff): the launcher script finds it before this one.
  app.footer("Also: diff (plan changes seen in a recorded run: fploc map diff --help)");
  bool as_json = false;

  PlanArgs b_plan;
  AnnfArgs b_annf;
  std::string b_out;
  auto* build = app.add_subcommand("build", "build an ANNF and save it as .fpmap");
  b_plan.add(build);
  b_annf.add(build);
  build->add_option("--out", b_out, "output .fpmap")->required();
  build->add_flag("--json", as_json, "JSON summary on stdout");

  PlanArgs v_plan;
  ValidateArgs v;
  auto* validate = app.add_subcommand("validate", "accuracy/speed table (paper's Table III) with baselines");
  v_plan.add(validate);
  validate->add_option("--depths", v.depths, "depth range, e.g. 3-8");
  validate->add_option("--samples", v.samples, "uniform samples in the plan's bounding box (default 1000000)");
  validate->add_option("--mode", v.mode, "paper | exact | both (default both)")->check(CLI::IsMember({"paper", "exact", "both"}));
  validate->add_option("--rule", v.rule, "paper stopping rule (default child-leaf-ordered)");
  validate->add_flag("--distinct,!--no-distinct", v.distinct,
                     "paper mode: two nearest at distinct distances, as the authors' demo (default on)");
  validate->add_option("--candidates", v.candidates,
                       "paper mode: a field's two elements among all | passing (elements passing through it; else all; "
                       "default) | passing-inherit (else the parent's two)")
      ->check(CLI::IsMember({"all", "passing", "passing-inherit"}));
  validate->add_option("--hit-by", v.hit_by,
                       "distance (default: a hit is any element at the true nearest distance, so ties and duplicates "
                       "count) | id (only the brute-force element, the lowest id among ties)")
      ->check(CLI::IsMember({"distance", "id"}));
  validate->add_option("--sample-area", v.sample_area, "bbox (plan's bounding box, default) | fields (area of the root fields)");
  validate->add_flag("--all-rules", v.all_rules, "measure every reading of the paper's stopping rules");
  validate->add_option("--root", v.root, "root field length in metres (default 6)");
  validate->add_option("--margin", v.margin, "metres of field around the plan's bounding box (default 2)");
  validate->add_option("--max-candidates", v.max_candidates, "exact mode: subdivide while a leaf has more candidates (default 2)");
  validate->add_option("--refine", v.refine, "exact mode: candidate refinement levels (default 2)");
  validate->add_option("--exact-depth", v.exact_depth, "exact mode rows: extra depth added (default 0)");
  validate->add_option("--baseline-depth", v.baseline_depth, "KD-tree spacing / grid resolution = leaf length at this depth (default 7)");
  validate->add_option("--seed", v.seed, "random seed");
  validate->add_flag("--no-baselines", v.no_baselines, "skip the baselines");
  validate->add_flag("--json", as_json, "JSON on stdout");

  PlanArgs r_plan;
  RenderArgs r;
  auto* render = app.add_subcommand("render", "SVG/PNG of the plan and the leaf fields coloured by nearest element, with a "
                                     "scale bar and a grid in plan metres labelled along the left and bottom edges");
  r_plan.add(render);
  render->add_option("--map", r.map, "a built .fpmap (default: build a paper-mode field)");
  render->add_option("--depth", r.depth, "depth when building (default 5, like the paper's Fig. 2)");
  render->add_option("--out", r.out, "output .svg or .png")->required();
  render->add_option("--width", r.width, "image width in pixels (PNG) / user units (SVG)");
  render->add_option("--fields", r.fields, "nearest: the look-up's leaf fields coloured by their nearest element (as the "
                     "paper's Fig. 2); none: the plan's lines only, without building the fields (fast on a large plan). Default: "
                     "nearest, but none for a plan-change drawing of `fploc map diff` (a DXF with FPLOC-* layers)")
      ->check(CLI::IsMember({"nearest", "none"}));

  PlanArgs p_plan;
  PgmArgs p;
  auto* pgm = app.add_subcommand("export-pgm", "ROS map_server occupancy map (PGM + YAML)");
  p_plan.add(pgm);
  pgm->add_option("--resolution", p.resolution, "metres per pixel")->required();
  pgm->add_option("--out", p.out, "output directory")->required();
  pgm->add_option("--name", p.name, "file name stem (default map)");
  pgm->add_option("--margin", p.margin, "free border around the plan in metres (default 1)");
  pgm->add_option("--thickness", p.thickness, "wall thickness drawn in metres (default: one pixel)");
  pgm->add_flag("--json", as_json, "JSON summary on stdout");

  PlanArgs c_plan, c_ref;
  CompareArgs c;
  auto* compare = app.add_subcommand("compare", "share of one plan's length within a tolerance of another (e.g. IFC vs DXF)");
  c_plan.add(compare);
  c_ref.add(compare, "ref-");
  compare->add_option("--tolerance", c.tolerance, "metres (default 0.05)");
  compare->add_option("--step", c.step, "sampling step along the plan's elements in metres (default 0.02)");
  compare->add_option("--align", c.align, "none | auto (rigid 2D: ICP from the identity and from the box centres, default)")
      ->check(CLI::IsMember({"none", "auto"}));
  compare->add_option("--out", c.out, "overlay (.png or .svg): reference grey, plan green within tolerance, red beyond");
  compare->add_option("--transform", c.transform, "x,y,yaw_deg applied to the plan first (e.g. an alignment found before)");
  compare->add_flag("--json", as_json, "JSON on stdout");

  CLI11_PARSE(app, argc, argv);
  // nan, inf: one error naming the option (--resolution inf wrote a 0 x 0 map).
  if (!fploc::rt::check_finite_options(app, "fploc map: error", std::cerr)) return 1;
  // --width -5 wrote a 16 x 16 PNG.
  if (*render && r.width <= 0) {
    std::cerr << "fploc map: error: --width must be > 0 (pixels / SVG user units), got " << r.width << "\n";
    return 1;
  }
  try {
    if (*build) return cmd_build(b_plan, b_annf, b_out, as_json);
    if (*validate) return cmd_validate(v_plan.load(), v, as_json);
    if (*render) {
      FloorPlan plan = r_plan.load();
      // A building description's stairs, ramps and lifts that reach the floor drawn (an IFC file has none).
      std::string ext = std::filesystem::path(r_plan.plan).extension().string();
      for (auto& ch : ext) ch = char(std::tolower((unsigned char)ch));
      if (ext == ".pbtxt") {
        BuildingLoadOptions bo;
        bo.quiet = true;
        const Building bld = load_building(r_plan.plan, bo);
        r.floor = bld.floor(r_plan.floor).name;
        for (const auto& c : bld.connections)
          if (c.from_floor == r.floor || c.to_floor == r.floor) r.connections.push_back(c);
      }
      return cmd_render(plan, r);
    }
    if (*pgm) return cmd_export_pgm(p_plan.load(), p, as_json);
    if (*compare) return cmd_compare(c_plan.load(), c_ref.load(), c, as_json);
  } catch (const std::exception& e) {
    std::cerr << "fploc map: error: " << e.what() << "\n";
    return 1;
  }
  return 2;
}
