// The project's demo building (authored here in code; the plans are shipped as
// data/buildings/demo-building/{ground,first}.json and described by data/buildings/demo-building.pbtxt):
// two floors 3.2 m apart, 34 x 20 m, joined by a straight ramp along the north wall (25.6 m, 12.5 %),
// a lift with doors on two opposite sides (car 2.4 x 2.4 m) and stairs (not driven). Ground floor: a
// west hall with a double-height atrium (columns at its corners), an office behind a partition with a
// doorway, a lift lobby behind another; first floor: the atrium gallery (walled), offices, the lobby
// under a sloped roof. Doorways 1.0-1.2 m wide (the simulator puts 2-3 cm thresholds across them).
//
// Journeys through it (scenarios.h): building-twofloor (ground floor, up the ramp, across the first
// floor into the lift, down, through two doorways on the ground floor), building-ramp (up the ramp and
// on to the first floor's lobby), building-thresholds (ground floor, lobby -> office -> hall through
// two doorways).
#pragma once
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/sim/journey.h"

namespace fploc::sim {

// "ground" or "first"; throws std::invalid_argument otherwise.
FloorPlan demo_building_plan(const std::string& floor);
std::vector<std::string> demo_building_floors();
// The legs of a journey base name ("building-twofloor", "building-ramp", "building-thresholds"); empty
// for other names.
std::vector<JourneyLeg> demo_building_journey(const std::string& base);

}  // namespace fploc::sim
