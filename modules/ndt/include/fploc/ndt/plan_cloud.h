// The point-cloud map of the NDT peer: the floor plan extruded to a height band, as the map an
// hdl_localization user would build from the drawing (walls as vertical surfaces, no floor or ceiling:
// the plan says nothing about them). Points every `spacing_m` along each element and in height.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::ndt {

struct PlanCloudOptions {
  double z_min_m = 0.0;     // band of the extruded walls (plan frame: z = 0 is the floor)
  double z_max_m = 3.0;
  double spacing_m = 0.1;   // along the elements and in height
};

// Plan-frame points (x, y, z) on every element of the plan; throws std::invalid_argument for an empty
// band or a spacing <= 0.
std::vector<Eigen::Vector3f> plan_cloud(const FloorPlan& plan, const PlanCloudOptions& o = {});

}  // namespace fploc::ndt
