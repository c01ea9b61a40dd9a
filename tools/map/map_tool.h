#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/floorplan/building.h"
#include "fploc/floorplan/plan.h"

namespace fploc {

struct ValidateArgs {
  std::string depths = "3-8";
  long samples = 1000000;
  std::string mode = "both";
  std::string rule = "child-leaf-ordered";
  bool all_rules = false;
  bool distinct = true;
  std::string candidates = "passing";
  std::string hit_by = "distance";
  std::string sample_area = "bbox";
  double root = 6.0;
  double margin = 2.0;
  int max_candidates = 2;
  int refine = 2;
  int exact_depth = 0;
  int baseline_depth = 7;
  uint32_t seed = 1;
  bool no_baselines = false;
};
int cmd_validate(const FloorPlan& plan, const ValidateArgs& a, bool as_json);

struct RenderArgs {
  std::string map, out;
  // "nearest": the look-up's leaf fields coloured by nearest element; "none": lines only; "": nearest, but none for a
  // plan-change drawing (FPLOC-* layers of `fploc map diff`: its coloured lines were lost on the coloured fields)
  std::string fields;
  int depth = 5;
  int width = 1600;
  // A building floor's stairs, ramps and lifts (the building's connections from or to the floor), drawn over the
  // plan with a legend entry each; `floor` names the floor drawn.
  std::vector<FloorConnection> connections;
  std::string floor;
};
int cmd_render(const FloorPlan& plan, const RenderArgs& a);

struct PgmArgs {
  double resolution = 0.05;
  std::string out, name = "map";
  double margin = 1.0;
  double thickness = 0;
};
int cmd_export_pgm(const FloorPlan& plan, const PgmArgs& a, bool as_json);


struct CompareArgs {
  double tolerance = 0.05;  // metres
  double step = 0.02;       // sampling step along A's elements
  std::string align = "auto";
  std::string out;          // overlay image (.png or .svg)
  std::string transform;    // "x,y,yaw_deg": applied to the plan before the alignment
};
// Share of plan A's length within `tolerance` of plan B (after an optional rigid alignment).
int cmd_compare(const FloorPlan& a, const FloorPlan& b, const CompareArgs& args, bool as_json);

}  // namespace fploc
