// Which floor a node's `plan` option (PlanSource) names: index in the building's floor list and the
// floor's name, as pose_t / frame_pose_t carry them. A single plan is floor 0 named "0".
#pragma once
#include <string>

#include "options/common.pb.h"

namespace fploc::config {

struct FloorRef {
  int index = 0;          // -1: unknown (an IFC storey other than the lowest: its index needs the model)
  std::string name = "0";
  double elevation = 0;   // the floor's elevation [m]: pose_t z is absolute (elevation + height above it)
};

// `path` is the option's file as resolved by the node. A building (.pbtxt) is read (not its plans) to
// find the floor; throws naming the known floors when plan.floor() is not one of them.
FloorRef floor_ref(const PlanSource& plan, const std::string& path);

}  // namespace fploc::config
