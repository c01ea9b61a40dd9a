// plan_diff_t -> the elements the plan-change detector flagged (for the matcher's and the optimizer's
// per-element weights, fploc/matcher/element_weights.h). Pure mapping.
#pragma once
#include <fploc/plan_diff_t.hpp>

#include <vector>

#include "fploc/matcher/element_weights.h"

namespace fploc::adapters {

// MISSING and MOVED items with an element id (NEW items carry -1 and are skipped).
std::vector<matcher::FlaggedElement> flagged_elements(const plan_diff_t& m);

}  // namespace fploc::adapters
