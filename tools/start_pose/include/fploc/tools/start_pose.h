// A start pose (x, y) against the plan a localizing node of a graph uses: far outside its extent, just
// outside, within the extent but not inside the drawn walls (fploc/floorplan/plan_position.h), or inside.
// Shared by `fploc replay` (a warning per node whose options' initial_pose is off its plan) and `fploc node
// initial-pose` (refuses a pose far outside, warns for the rest).
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "fploc/floorplan/io.h"
#include "fploc/floorplan/plan_position.h"
#include "fploc/runtime/graph.h"

namespace fploc::tools {

// Farther than this outside the plan's extent a start pose is taken for a typo, the wrong plan or another
// frame (`fploc node initial-pose` refuses it); nearer, a robot at a door outside the drawn walls.
inline constexpr double kFarOutsideM = 2.0;

// A localizing node of the graph: options with a `plan` (PlanSource, file set) and an `initial_pose` field.
struct StartPlan {
  std::string node;
  std::string path;            // the plan file, resolved against the graph's folder
  PlanLoadOptions load;        // layers, units, floor of the option (quiet)
  bool has_initial_pose = false;
  double x = 0, y = 0;         // the options' initial_pose (when set)
  // The node ignores its initial_pose option (the matcher's wait_for_initial_pose: it waits for a pose on its port;
  // amcl's global_localization): `fploc replay` does not warn about it.
  bool ignores_initial_pose = false;
};

// Every enabled node of the graph with such options that `keep` accepts (all when empty).
std::vector<StartPlan> start_plans(const rt::LoadedGraph& g,
                                   const std::function<bool(const fploc::Node&)>& keep = {});

enum class StartPoseKind { kInside, kNotEnclosed, kNearOutside, kFarOutside };

struct StartPoseCheck {
  StartPoseKind kind = StartPoseKind::kInside;
  PlanPosition where;
  // A building (.pbtxt, .ifc): the floor checked (plan.floor; "" = the first floor listed, IFC: the lowest storey), and
  // the other floors whose plan's extent holds (x, y) (the pose has no z: plan.floor picks the floor).
  std::string floor;
  std::vector<std::string> other_floors;
  // "(X, Y) lies outside its plan's extent (x A .. B, y C .. D m, PATH)" and the like (PATH: "floor 'F' of PATH" in a
  // building, then "; it lies inside floor 'G' (--set NODE.plan.floor=G to start there)"); "" when inside.
  std::string text;
};

// Loads the node's plan (throws std::runtime_error naming the file or the floors) and places (x, y) on it.
StartPoseCheck check_start_pose(const StartPlan& plan, double x, double y);

}  // namespace fploc::tools
