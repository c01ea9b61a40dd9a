// Ramps and stairs of a building (fploc/floorplan/building.h) as inclined surfaces: the geometry both the
// simulator (its ground) and the localizer (the floor's height under the robot, for pose z across
// floors) read from a RAMP or STAIRS connection.
//
// Convention (proto/building.proto, FloorConnectionSpec): the connection's polygon has 4 vertices; the
// edge v0-v1 is the foot (on `from_floor`), the edge v2-v3 the head (on `to_floor`); the surface rises
// linearly from the foot edge's midpoint to the head edge's midpoint by the difference of the two floors'
// elevations. Stairs are the same plane (their steps are not modelled).
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "fploc/floorplan/building.h"

namespace fploc {

// A ramp or stairs between two floors, in the building's x/y frame and absolute heights.
struct Incline {
  std::string name;
  ConnectionKind kind = ConnectionKind::kRamp;
  int from_floor = -1, to_floor = -1;   // foot and head floors (indices into Building::floors)
  std::vector<Eigen::Vector2d> polygon;
  Eigen::Vector2d foot = Eigen::Vector2d::Zero(), head = Eigen::Vector2d::Zero();  // edge midpoints
  double z_foot = 0, z_head = 0;        // absolute surface heights there
  // Position along the incline: 0 at the foot, 1 at the head (not clamped).
  double tau(const Eigen::Vector2d& p) const;
  // The absolute surface height at p (the plane, not clamped: use inside the polygon).
  double z_at(const Eigen::Vector2d& p) const { return z_foot + tau(p) * (z_head - z_foot); }
  bool contains(const Eigen::Vector2d& p) const;
};

// Every RAMP and STAIRS connection of the building as an Incline. Throws naming the connection when its
// polygon is not a quadrilateral or its floors have the same elevation.
std::vector<Incline> building_inclines(const Building& b);

}  // namespace fploc
