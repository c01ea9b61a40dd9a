// Where a point lies relative to a floor plan: how far outside the plan's extent (its bounding box), and,
// inside it, whether it is within the drawn walls (rays from the point meet a plan element in most
// directions) or in the open within the box (beside an L-shaped building, in a courtyard). For start poses
// typed by hand (a matcher's initial_pose, `fploc node initial-pose`): a typo, the wrong plan or another frame
// starts a run that is LOST from the first scan.
//
//   const PlanPosition w = locate_in_plan(plan, {x, y});
//   if (w.outside_m > 2) ...          // far outside the drawn building
//   else if (!w.enclosed()) ...       // in the box, not between walls
#pragma once
#include <Eigen/Core>

#include "fploc/floorplan/plan.h"

namespace fploc {

struct PlanPosition {
  Box2 extent;            // the plan's bounds
  double outside_m = 0;   // distance from the point to the extent (0 inside it; inf for a non-finite point)
  int directions = 0;     // rays cast (only inside the extent; 0 otherwise)
  int hits = 0;           // of them, those that meet a plan element
  bool inside_extent() const { return outside_m == 0; }
  // Inside the extent and plan elements in more than half the directions. From a point outside a building's
  // convex hull the building spans less than 180 degrees, so at most half the rays can meet it; within walls
  // all do but the few that leave through a doorway or a window.
  bool enclosed() const { return inside_extent() && 2 * hits > directions; }
};

// `directions` rays evenly spaced from angle 0, each long enough to cross the whole plan.
PlanPosition locate_in_plan(const FloorPlan& plan, const Eigen::Vector2d& p, int directions = 16);

}  // namespace fploc
