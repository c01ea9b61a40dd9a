// Internal to modules/sim (perturb.cpp): "doors moved", a renovation that shifts a doorway along its wall.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "fploc/core/rng.h"
#include "fploc/sim/perturb.h"

namespace fploc::sim::detail {

// Shifts up to `n` of the plan's doorways (find_doorways) along their wall by min_m..max_m (either way):
// the wall ends at both jambs (both faces of a wall drawn with two lines) and the jamb segments move
// along the wall, so one wall grows over part of the old opening and the other loses a piece to the new
// one. `cur` is the world geometry of each plan element (edited), `w` gets the truth (elements marked
// kDoorMoved, w.doors_moved). Doorways the path goes through, or whose shortened wall would fall below
// 0.5 m, are left alone.
void move_doors(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& path, int n, double min_m, double max_m,
                Rng& rng, std::vector<Element>& cur, WorldEdit& w);

}  // namespace fploc::sim::detail
