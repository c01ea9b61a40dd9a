// The ceilings of one floor of a building, as data: a default floor-to-ceiling height, areas with their
// own height (a lower corridor, a drop ceiling, a double-height atrium), sloped or missing, and ceiling
// clutter (lamps, beams, ducts, the T-bars of a drop-ceiling grid) hanging below them. Small on purpose,
// so a building description (one floor's default height and its areas) can fill it; the simulator turns
// it into world geometry (apply_ceiling_map), and the named ceiling kinds (make_ceiling_map) make the
// `building-*` scenarios on any plan, deterministic by seed.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::sim {

class World;

struct CeilingArea {
  std::string name;                                  // "corridor", "atrium", ... (diagnostics)
  Box2 box;                                          // plan frame [m] (axis-aligned for now)
  double height_m = 3.0;                             // floor-to-ceiling height at box.min
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();   // dz/dx, dz/dy (a sloped ceiling under a roof)
  bool open = false;                                 // no ceiling (an opening: rays pass)
  double height_at(const Eigen::Vector2d& p) const { return height_m + slope.dot(p - box.min); }
};

// A box hanging from the ceiling: a lamp, a beam, a duct, a grid T-bar. Not in the plan.
struct CeilingObject {
  std::string kind;                                  // lamp | beam | duct | grid
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double yaw = 0;
  Eigen::Vector2d half = Eigen::Vector2d(0.3, 0.3);  // half extents in its own frame
  double z0 = 2.6, z1 = 3.0;                         // bottom and top above the floor [m]
};

struct CeilingMap {
  double default_height_m = 3.0;
  std::vector<CeilingArea> areas;       // disjoint; outside them the default height
  std::vector<CeilingObject> objects;
  // Floor-to-ceiling height at a plan point (NaN in an opening).
  double height_at(const Eigen::Vector2d& p) const;
};

// Named kinds for scenarios: "areas" (a low corridor band, a drop ceiling, a high hall, a sloped roof
// corner), "atrium" (a double-height centre), "clutter" (lamps, beams, ducts, a drop-ceiling grid on the
// default ceiling), "mixed" (the areas with the hall at double height, and the clutter). Deterministic for (kind, bounds, seed).
// Throws std::invalid_argument naming the valid kinds.
CeilingMap make_ceiling_map(const std::string& kind, const Box2& bounds, double default_height_m, uint64_t seed);
std::vector<std::string> ceiling_map_kinds();
// The map as one floor of a building description (proto/building.proto text): the plan the world was built
// from (its file, layer globs and units override: the areas are in that plan's frame, metres), elevation 0,
// the default height and the areas in their order (boxes as polygons; sloped ones as sloped_ceiling with the
// box's min corner as origin; openings left out: no ceiling to look up). Read back with load_building, every
// point under the ceiling gets the height the rays hit (segmentation building_ceilings_test). The hanging
// objects (lamps, beams, ducts, grid T-bars) are not part of a building file: the segmenter must cope with
// them. For benches: the segmenter given the building's heights.
std::string ceiling_map_building_text(const CeilingMap& m, const std::string& plan_file, const std::string& floor = "0",
                                      const std::vector<std::string>& layers = {}, const std::string& units = "");
// Adds the areas (as ceiling patches) and the objects (as clutter boxes) to the world.
void apply_ceiling_map(const CeilingMap& m, World& world);

}  // namespace fploc::sim
