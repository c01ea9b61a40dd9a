// plandiff::Diff (modules/plandiff) <-> plan_diff_t (FPLOC_PLAN_DIFF): the missing and moved plan
// elements (moved ones drawn where they were seen) and the new structure, with the run's counts.
#pragma once

#include <fploc/plan_diff_t.hpp>

#include <cstdint>

#include "fploc/floorplan/plan.h"
#include "fploc/plandiff/plan_diff.h"

namespace fploc::adapters {

// Item kinds in plan_diff_t.kind.
enum class PlanDiffKind : int8_t { kMissing = 1, kMoved = 2, kNew = 3 };

plan_diff_t to_msg(const plandiff::Diff& d, const FloorPlan& plan, int64_t utime, int64_t seq);

}  // namespace fploc::adapters
