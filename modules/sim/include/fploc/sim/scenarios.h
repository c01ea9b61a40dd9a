// The project's demo floor plans (a paper-like room and corridor, authored here in code and shipped as
// data/plans/*.json) and the named scenarios of DESIGN.md:
//   room-small-loop | room-large-loop | room-no-loop | corridor-loop  + -slow | -medium | -fast
//   auto-loop-slow | auto-loop-medium | auto-loop-fast   (a loop planned through any plan's free space)
//   building-areas | building-atrium | building-clutter | building-mixed  + -slow | -medium | -fast
//     (auto-loop under the ceilings of a real building, ceiling_map.h)
//   building-twofloor | building-ramp | building-thresholds  + -slow | -medium | -fast
//     (journeys through the demo building data/buildings/demo-building.pbtxt: demo_building.h)
// Lengths and speeds are the paper's (Tables I and II) per sequence.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/sim/journey.h"
#include "fploc/sim/motion.h"

namespace fploc::sim {

// ~200 m^2 room (16 x 12.5 m inside, 0.25 m walls): two doors on the west and east walls, windows on the
// south and north walls (layer "windows"), two square and two round pillars (layer "columns"), short
// corridors outside the doors.
FloorPlan demo_room_plan();
// Four bent, self-similar corridors around a central block (each ~20.7 m along its centre line, a 3.0 m
// wide half and a 1.6 m wide half), a ~82 m loop.
FloorPlan demo_corridor_plan();
constexpr double kRoomCeilingM = 3.2;
constexpr double kCorridorCeilingM = 2.6;

struct ScenarioSpec {
  std::string name;        // full name, e.g. "room-small-loop-fast"
  std::string base;        // "room-small-loop", ..., "auto-loop"
  std::string speed_name;  // slow | medium | fast
  std::string plan_kind;   // "room", "corridor", "any" (auto-loop) or "building" (a journey through the demo building)
  std::vector<Eigen::Vector2d> control;  // B-spline control polygon (empty for auto-loop)
  bool closed = true;
  double length = 0;       // target path length [m] (0 = as planned)
  SpeedSpec speed;
  double ceiling_m = 3.0;
  std::string ceilings;    // building-*: the ceiling_map.h kind ("areas", "atrium", "clutter", "mixed")
  std::vector<JourneyLeg> legs;  // plan_kind "building": the journey (demo_building.h)
};

// Fills `out` for a scenario name; false with a message listing the valid names.
bool scenario_spec(const std::string& name, ScenarioSpec& out, std::string* error);
std::vector<std::string> scenario_names();

}  // namespace fploc::sim
