#include "fploc/sim/demo_building.h"

#include <stdexcept>

namespace fploc::sim {
namespace {

using V = Eigen::Vector2d;

void seg(FloorPlan& p, int layer, V a, V b) { p.elements.push_back(Element::segment(a, b, layer)); }

// Shared by both floors: the outer walls, the ramp corridor's side wall, the lift shaft (doors 1.2 m
// wide on its south and north sides), the stairs' side wall, the atrium's corner columns.
void common(FloorPlan& p) {
  const int walls = p.layer_index("walls"), lift = p.layer_index("lift"), cols = p.layer_index("columns");
  seg(p, walls, V(0, 0), V(34, 0));
  seg(p, walls, V(34, 0), V(34, 20));
  seg(p, walls, V(34, 20), V(0, 20));
  seg(p, walls, V(0, 20), V(0, 0));
  seg(p, walls, V(4, 17.5), V(29.6, 17.5));    // ramp corridor (y 17.5-20, x 4-29.6)
  seg(p, walls, V(16, 15.5), V(20.5, 15.5));   // stairs (y 15.5-17.5, x 16-20.5)
  seg(p, lift, V(28, 6), V(28, 8.4));
  seg(p, lift, V(30.4, 6), V(30.4, 8.4));
  for (double y : {6.0, 8.4}) {
    seg(p, lift, V(28, y), V(28.6, y));
    seg(p, lift, V(29.8, y), V(30.4, y));
  }
  for (V c : {V(5, 5), V(12, 5), V(5, 13), V(12, 13)}) p.elements.push_back(Element::circle(c, 0.25, cols));
}

}  // namespace

std::vector<std::string> demo_building_floors() { return {"ground", "first"}; }

FloorPlan demo_building_plan(const std::string& floor) {
  FloorPlan p;
  p.source = "demo building, floor " + floor + " (fploc::sim::demo_building_plan)";
  common(p);
  const int walls = p.layer_index("walls"), cols = p.layer_index("columns");
  if (floor == "ground") {
    seg(p, walls, V(29.6, 17.5), V(29.6, 20));  // the ramp's head is on the first floor: closed here
    seg(p, walls, V(20.5, 15.5), V(20.5, 17.5));  // the stairs' head likewise
    seg(p, walls, V(14, 0), V(14, 8));          // hall | office, doorway y 8-9
    seg(p, walls, V(14, 9), V(14, 17.5));
    seg(p, walls, V(24, 0), V(24, 2.5));        // office | lobby, doorway y 2.5-3.5
    seg(p, walls, V(24, 3.5), V(24, 17.5));
    p.elements.push_back(Element::circle(V(19, 11), 0.3, cols));
    p.elements.push_back(Element::circle(V(29.2, 13.5), 0.3, cols));
  } else if (floor == "first") {
    seg(p, walls, V(4, 17.5), V(4, 20));        // the ramp's foot is on the ground floor: closed here
    seg(p, walls, V(16, 15.5), V(16, 17.5));    // the stairs' foot likewise
    // The atrium gallery (walled on this floor).
    seg(p, walls, V(5, 5), V(12, 5));
    seg(p, walls, V(12, 5), V(12, 13));
    seg(p, walls, V(12, 13), V(5, 13));
    seg(p, walls, V(5, 13), V(5, 5));
    seg(p, walls, V(14, 0), V(14, 4));          // gallery | offices, doorway y 4-5
    seg(p, walls, V(14, 5), V(14, 17.5));
    seg(p, walls, V(24, 0), V(24, 12));         // offices | lobby, doorway y 12-13
    seg(p, walls, V(24, 13), V(24, 15.5));
    seg(p, walls, V(14, 9), V(20, 9));          // a meeting room in the offices, doorway x 20-21
    seg(p, walls, V(21, 9), V(24, 9));
    p.elements.push_back(Element::circle(V(27.5, 3.5), 0.3, cols));
  } else {
    throw std::invalid_argument("demo building: no floor '" + floor + "' (floors: ground, first)");
  }
  return p;
}

std::vector<JourneyLeg> demo_building_journey(const std::string& base) {
  // Ground floor, west hall -> north along the west wall -> up the ramp (x 4 -> 29.6 at y 18.75).
  const std::vector<V> to_ramp = {V(10, 2.5), V(7, 2.5), V(4, 2.5), V(2.4, 3.6), V(2.2, 6),  V(2.2, 10),
                                  V(2.2, 14), V(2.4, 16.8), V(3.4, 18.6), V(5, 18.75), V(8, 18.75), V(12, 18.75),
                                  V(16, 18.75), V(20, 18.75), V(24, 18.75), V(28, 18.75), V(30, 18.75)};
  // First floor: out of the ramp, south along the east wall, into the lift from the north (stops at the
  // car's centre heading south).
  const std::vector<V> to_lift = {V(31.3, 18.6), V(32.5, 17.2), V(32.6, 15), V(32.3, 13.2), V(30.8, 12.2),
                                  V(29.3, 11.6), V(29.2, 10.4), V(29.2, 9.4), V(29.2, 8.4), V(29.2, 7.2)};
  // Ground floor from the lift (heading south) through the lobby | office doorway (y 3) and the office |
  // hall doorway (y 8.5) into the atrium.
  const std::vector<V> from_lift = {V(29.2, 7.2), V(29.2, 6.0), V(29.2, 4.8), V(28.8, 3.4), V(27.4, 3.0),
                                    V(26, 3.0),   V(24.8, 3.0), V(23.2, 3.0), V(22, 3.0),   V(19.5, 3.6),
                                    V(17.2, 5.6), V(15.8, 8.3), V(15.2, 8.5), V(14.4, 8.5), V(13.6, 8.5),
                                    V(12.6, 8.5), V(10.5, 8.8), V(8.5, 9.5)};
  if (base == "building-twofloor") {
    std::vector<V> leg1 = to_ramp;
    leg1.insert(leg1.end(), to_lift.begin(), to_lift.end());
    return {{"ground", leg1}, {"ground", from_lift}};
  }
  if (base == "building-ramp") {
    std::vector<V> leg = to_ramp;
    leg.insert(leg.end(), {V(31.3, 18.6), V(32.5, 17.2), V(32.6, 15), V(32.6, 13)});
    return {{"ground", leg}};
  }
  if (base == "building-thresholds") {
    std::vector<V> leg = {V(32, 2.2), V(31, 2.6)};
    leg.insert(leg.end(), from_lift.begin() + 4, from_lift.end());
    return {{"ground", leg}};
  }
  return {};
}

}  // namespace fploc::sim
