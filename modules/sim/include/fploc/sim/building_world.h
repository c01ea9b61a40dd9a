// The simulated world of one floor of a building (fploc/floorplan/building.h): the floor's plan as walls,
// its ceilings from the building (the default height and the areas: polygons, flat or sloped), the ground
// that is not flat (ramps and stairs between floors, from the building's RAMP and STAIRS connections) and
// door thresholds (2-3 cm bumps across every doorway of the plan, heights seeded). Coordinates are
// relative to the floor: its finished floor is z = 0 (absolute z = floor elevation + z).
//
// Ramp and stairs geometry from a connection polygon (4 vertices): the edge v0-v1 is the foot (on
// `from_floor`), the edge v2-v3 the head (on `to_floor`); the surface rises linearly from the foot's
// midpoint to the head's midpoint by the difference of the two floors' elevations.
//
// A lift car (LIFT connection polygon) with its doors closed is a world of its own: make_lift_car_world.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fploc/floorplan/building.h"
#include "fploc/floorplan/incline.h"
#include "fploc/sim/world.h"

namespace fploc::sim {

// A door threshold: a strip across the doorway a-b, `height` tall and `width` deep (along the path).
struct Threshold {
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
  double height = 0.025;
  double width = 0.06;
};

// Ramps and stairs: fploc/floorplan/incline.h (shared with the localizer's pose z across floors).
using fploc::Incline;
using fploc::building_inclines;

// The ground of one floor as seen by the wheels: inclines touching the floor, thresholds.
struct FloorGround {
  double elevation = 0;
  std::vector<Incline> inclines;     // those with from_floor or to_floor == this floor
  std::vector<Threshold> thresholds;
  // Surface height relative to the floor (inclines; 0 elsewhere), thresholds not included.
  double surface_at(const Eigen::Vector2d& p) const;
  // Height of a wheel's contact relative to the floor: the surface plus the threshold profile a wheel of
  // radius `wheel_radius_m` rolling over a threshold strip follows (a short jolt, not a ramp).
  double wheel_at(const Eigen::Vector2d& p, double wheel_radius_m = 0.04) const;
};

struct FloorWorldOptions {
  bool thresholds = true;            // thresholds across the plan's doorways
  double threshold_min_m = 0.02, threshold_max_m = 0.03;
  uint64_t seed = 0;
};

// The world of floor `floor` (index) with its plan (already loaded with the layers/units wanted).
// `ground` receives the floor's ground (for the trajectory). `note` says what was added.
std::unique_ptr<World> make_floor_world(const Building& b, int floor, const FloorPlan& plan, const FloorWorldOptions& o,
                                        FloorGround* ground, std::string* note = nullptr);

// The closed lift car: the connection polygon as walls, its floor at z = 0 and a ceiling `car_height_m` up.
std::unique_ptr<World> make_lift_car_world(const FloorConnection& lift, double car_height_m = 2.4);

// The plan elements a path must not cross on `floor`: the outlines of the floor's stairs (never driven),
// and of its ramps and lifts unless `allow_connections` (auto-loop keeps to the floor), each filled with
// a fan of segments from its centroid (no free space inside).
std::vector<Element> connection_outlines(const Building& b, int floor, bool allow_connections);

}  // namespace fploc::sim
