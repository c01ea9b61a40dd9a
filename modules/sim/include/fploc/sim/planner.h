// auto-loop: plans a smooth, collision-free closed loop through the free space of any floor plan.
//
// The plan is rasterised, an exact Euclidean distance transform gives the clearance of every cell, and for a
// few offsets D (1.0 m down to clearance + 0.15 m) the connected regions {clearance >= D} (as they are, and
// morphologically opened by a 0.5 m disc to drop thin spurs) that do not touch the grid border (the outside
// of a closed building) are found. The outer boundary of the region with the
// longest boundary (preferring larger D when the lengths are close) is traced, smoothed and used as the
// control polygon of a closed cubic B-spline; the final path is checked against the exact distance to every
// plan element and D is raised when it comes closer than `clearance_m`.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::sim {

struct AutoLoopConfig {
  double clearance_m = 0.4;     // hard minimum distance from every plan element
  double resolution_m = 0;      // grid cell (0 = from the plan size, 0.05..0.2 m)
  double max_offset_m = 1.0;    // preferred distance from the walls
};

struct AutoLoopResult {
  std::vector<Eigen::Vector2d> control;  // closed B-spline control polygon
  double offset_m = 0;                   // D used
  double min_clearance_m = 0;            // exact minimum clearance of the B-spline path
  double length_m = 0;                   // path length
  std::string info;
};

// Throws std::runtime_error when the plan has no enclosed free space wide enough.
AutoLoopResult plan_auto_loop(const FloorPlan& plan, const AutoLoopConfig& cfg = {});

// Exact minimum distance from a set of points to the plan's elements.
double min_clearance(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& pts);

}  // namespace fploc::sim
