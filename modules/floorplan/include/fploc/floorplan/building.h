// A building: floors (each with a floor plan, an elevation and ceilings) and the connections
// between floors (stairs, ramps, lifts). Schema and text format: proto/building.proto.
//
//   Building b = fploc::load_building("data/buildings/two-floors.pbtxt");
//   const BuildingFloor& f = b.floor("first");            // throws naming the known floors
//   FloorPlan plan = fploc::load_floor_plan(b, f.name);   // that floor's plan, in metres
//   double h = f.ceiling_height_at({2.0, 1.5});           // area ceiling, else the floor's default
//
// Accepted files (load_building dispatches on the extension):
//  - .pbtxt  a building description (errors "FILE:LINE: floor[1] (first): ceiling_height_m must be > 0");
//  - .ifc    an IFC2x3/IFC4 model, one floor per storey (fploc/floorplan/ifc.h);
//  - any plan file (.dxf/.csv/.json/.fpmap): a one-floor building (floor "0", elevation 0, ceiling
//    height unknown = 0).
// load_floor_plan(path, options) in io.h accepts buildings too: PlanLoadOptions::floor picks the
// floor ("" = the first floor listed; IFC: the lowest storey).
#pragma once
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "fploc/floorplan/io.h"
#include "fploc/floorplan/plan.h"

namespace fploc {

struct CeilingArea {
  std::string name;
  std::vector<Eigen::Vector2d> polygon;  // >= 3 vertices
  // Height above the floor at p: height + slope.dot(p - origin) (slope zero for a flat ceiling).
  double height = 0;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();
  bool sloped() const { return slope.x() != 0 || slope.y() != 0; }
  bool contains(const Eigen::Vector2d& p) const;
  double height_at(const Eigen::Vector2d& p) const { return height + slope.dot(p - origin); }
};

struct BuildingFloor {
  std::string name;
  // Where the plan comes from: a file (absolute or relative to the working directory once loaded),
  // its layer globs, units override and, for IFC, the storey name.
  std::string plan_file;
  std::vector<std::string> layers;
  std::string units;
  std::string plan_floor;
  // Set when the plan is already in memory (IFC storeys); then plan_file is only for messages.
  std::shared_ptr<const FloorPlan> plan;
  double elevation = 0;       // metres above the building's datum
  double ceiling_height = 0;  // default ceiling height above the floor; 0 = unknown
  std::vector<CeilingArea> areas;
  // The first area containing p, or nullptr.
  const CeilingArea* area_at(const Eigen::Vector2d& p) const;
  // Ceiling height above the floor at p: the area's, else the floor's default (0 = unknown).
  double ceiling_height_at(const Eigen::Vector2d& p) const;
};

enum class ConnectionKind : uint8_t { kStairs = 1, kRamp = 2, kLift = 3 };
const char* to_string(ConnectionKind k);

struct FloorConnection {
  std::string name;
  ConnectionKind kind = ConnectionKind::kStairs;
  std::string from_floor, to_floor;
  std::vector<Eigen::Vector2d> polygon;
  bool contains(const Eigen::Vector2d& p) const;
};

struct Building {
  std::string name;
  std::string source;  // the file it came from
  std::vector<BuildingFloor> floors;
  std::vector<FloorConnection> connections;
  // What the reader left out without failing, one line each (IFC: an element whose representation
  // item the reader does not handle, "m.ifc:29: #63=IFCWALL: warning: ..."); printed unless quiet.
  std::vector<std::string> warnings;
  // Index of the floor named `name` ("" = 0); -1 when there is none.
  int floor_index(const std::string& name) const;
  // The floor named `name` ("" = the first); throws "SOURCE: no floor 'X' (floors: a, b)".
  const BuildingFloor& floor(const std::string& name) const;
};

// Options for reading IFC files (and building floors whose plan is an IFC file).
struct BuildingLoadOptions {
  double ifc_cut_height = 1.0;  // metres above each storey's floor at which IFC elements are cut
  bool quiet = false;
};

// By extension: .pbtxt (building description), .ifc, else a plan file as a one-floor building.
// Throws std::runtime_error with "FILE:LINE: field: message" for a bad description.
Building load_building(const std::string& path, const BuildingLoadOptions& options = {});
// Parses a building description from text; `source` names it in errors and is the folder plan
// paths are relative to (its parent directory).
Building parse_building(const std::string& text, const std::string& source);
// True for files load_building reads as buildings rather than plans (.pbtxt, .ifc).
bool is_building_file(const std::string& path);

// The plan of one floor (its layers/units unless `options` overrides them: non-empty layer globs or
// units replace the floor's). Throws naming the floor when it has no such plan.
FloorPlan load_floor_plan(const Building& building, const std::string& floor, const PlanLoadOptions& options = {});

}  // namespace fploc
