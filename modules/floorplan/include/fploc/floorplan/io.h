// Floor-plan input/output: DXF (ASCII), CSV and JSON of elements, and the plan stored inside a built
// map (.fpmap). Everything is converted to metres on load. Element ids (indices into
// FloorPlan::elements) are stable across save/load of JSON and .fpmap.
//
//   FloorPlan plan = fploc::load_floor_plan("walls.dxf", {"*WALL*", "*COLS*"}, "mm");
//
// Errors: std::runtime_error whose message starts with "FILE:LINE: " (text formats) or
// "FILE: ENTITY ...: " (DXF entity / JSON element), e.g.
//   "plan.csv:17: expected 4 numbers x1,y1,x2,y2, got 'a,b'".
//
// Formats
//  - .csv  rows `x1,y1,x2,y2[,layer]` (segments). An optional header row; blank lines and lines
//          starting with '#' are skipped. No unit in the file: metres unless units_override is given.
//  - .json {"units":"m","elements":[{"type":"segment","a":[x,y],"b":[x,y],"layer":"walls"},
//          {"type":"circle","c":[x,y],"r":0.3},
//          {"type":"arc","c":[x,y],"r":1,"start_deg":0,"end_deg":90}]}   (arcs counter-clockwise)
//          Only these keys: any other (a misspelt "unit", an element's "colour") is an error naming it.
//  - .dxf  ASCII DXF (see dxf.h for what is read). Binary DXF is a clear error.
//  - .fpmap the plan stored inside a map built by `fploc map build` (fploc/annf/annf.h).
//  - .yaml/.yml a ROS map_server occupancy map (YAML + PGM/PNG), vectorised (fploc/floorplan/occupancy.h).
//
// Layer globs (fnmatch-style `*`, `?`, `[..]`, case-insensitive) select elements by layer name; an
// empty list keeps everything. A selection that leaves no element is an error that lists the layers.
// CSV rows without a layer column are on layer "0".
#pragma once
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc {

// Every plan reader opens its input files through these, so a wrong path gets one clear error about
// the path instead of a reader's confusing one about the content: "PATH: cannot open (No such file or
// directory)", "PATH: is a directory", "PATH: empty file". Other non-regular files (pipes) are allowed.
void check_input_file(const std::string& path);
std::string read_input_file(const std::string& path);  // check_input_file, then the whole file

// Units accepted by `--units`: m, cm, mm, in (inch), ft. Returns metres per unit; throws on others.
double metres_per_unit(const std::string& units);

// Case-insensitive glob match (fnmatch, no special treatment of '/').
bool glob_match(const std::string& pattern, const std::string& text);
// True when `layer` matches any glob (or the list is empty).
bool layer_selected(const std::vector<std::string>& globs, const std::string& layer);

// Splits every entry on commas ("A,B" -> "A", "B"; empty parts dropped): one meaning of a layer list in
// every command (--layers) and option (plan.layers), applied by load_floor_plan.
std::vector<std::string> split_layer_globs(const std::vector<std::string>& lists);

struct PlanLoadOptions {
  std::vector<std::string> layer_globs;  // empty = all layers; entries may be comma-separated lists
  std::string units_override;            // "" = the file's own units (CSV: metres)
  bool quiet = false;                    // no notes on stderr (dropped entities etc.)
  // DXF only: robust extents. Entities farther than `outlier_factor` times the robust spread
  // (median absolute deviation based) from the median of all entity centres are dropped and reported.
  bool drop_outliers = true;
  double outlier_factor = 8.0;
  // DXF only: chord tolerance (metres) used to approximate ELLIPSE and SPLINE by segments.
  double curve_tolerance = 0.01;
  // Buildings (.pbtxt) and IFC files (fploc/floorplan/building.h): the floor (IFC: storey) whose plan
  // is loaded; "" = the first floor listed (IFC: the lowest storey).
  std::string floor;
  // IFC only: height above each storey's floor (metres) at which walls, columns, ... are cut.
  double ifc_cut_height = 1.0;
};

// Dispatch on the extension (.dxf, .csv, .json, .fpmap, .yaml/.yml map_server occupancy map; .pbtxt
// building and .ifc: the plan of options.floor, see fploc/floorplan/building.h; case-insensitive).
// `floor`: buildings and IFC only (PlanLoadOptions::floor).
FloorPlan load_floor_plan(const std::string& path, const std::vector<std::string>& layer_globs = {},
                          const std::string& units_override = "", const std::string& floor = "");
FloorPlan load_floor_plan(const std::string& path, const PlanLoadOptions& options);

// Individual readers (the `source` name is used in error messages).
FloorPlan read_plan_csv(std::istream& in, const std::string& source, const PlanLoadOptions& options = {});
FloorPlan read_plan_json(std::istream& in, const std::string& source, const PlanLoadOptions& options = {});

// Writers. JSON keeps every element kind exactly (units "m"). CSV holds segments only: circles and
// arcs are approximated by chords with at most `chord_tolerance` metres error. Throw on I/O errors.
void write_plan_json(const FloorPlan& plan, std::ostream& out);
void write_plan_csv(const FloorPlan& plan, std::ostream& out, double chord_tolerance = 0.005);
void save_floor_plan(const FloorPlan& plan, const std::string& path);  // by extension: .json or .csv

// Binary plan block used inside .fpmap files (little-endian, doubles). Versioned by the container.
void write_plan_binary(const FloorPlan& plan, std::ostream& out);
FloorPlan read_plan_binary(std::istream& in, const std::string& source);

// .fpmap container header (shared with fploc/annf): magic "FPLOCMAP", u32 version, then the plan
// block, then the ANNF block. Reading the plan only needs this module.
inline constexpr char kFpmapMagic[8] = {'F', 'P', 'L', 'O', 'C', 'M', 'A', 'P'};
inline constexpr uint32_t kFpmapVersion = 1;
// Reads and checks the header; throws "FILE: not an fploc map" / "FILE: map version N, this build
// reads version M (rebuild it with `fploc map build`)".
void read_fpmap_header(std::istream& in, const std::string& source);
FloorPlan read_plan_from_fpmap(const std::string& path);

// Keep only elements whose layer matches; renumbers layers. Throws "SOURCE: no elements on layers
// matching ..." when nothing is left and the plan was not empty.
void filter_layers(FloorPlan& plan, const std::vector<std::string>& globs);

// Scales every coordinate (and radius) by s.
void scale_plan(FloorPlan& plan, double s);

}  // namespace fploc
