// plandiff::Diff (modules/plandiff) <-> plan_diff_t (FPLOC_PLAN_DIFF): the missing and moved plan
// elements (moved ones drawn where they were seen) and the new structure, with the run's counts.
#pragma once

#include <fploc/plan_diff_t.hpp>
#include <fploc/segments_t.hpp>

#include <cstdint>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/matcher/element_weights.h"
#include "fploc/matcher/plan_scale.h"
#include "fploc/plandiff/plan_diff.h"

namespace fploc::adapters {

// Item kinds in plan_diff_t.kind.
// kLow: new straight structure seen only below plandiff::Options::new_min_height_m (furniture); its offset_m is the
// highest point seen on it above the floor (NaN: none).
enum class PlanDiffKind : int8_t { kMissing = 1, kMoved = 2, kNew = 3, kMissingPart = 4, kLow = 5 };

// The segmenter's wall points of a scan (FPLOC_SEGMENTS) levelled with its roll / pitch (as the features are:
// Ry(pitch) Rx(roll) p), and the sensor's height above the floor: how tall the new structure is. Empty points when
// the message is not OK or its attitude / height is not finite.
plandiff::PlanDiff::Heights heights_of(const segments_t& m);

plan_diff_t to_msg(const plandiff::Diff& d, const FloorPlan& plan, int64_t utime, int64_t seq);

// The MISSING and MOVED items with an element id (for the matcher's and the optimizer's per-element
// weights, fploc/matcher/element_weights.h); NEW items (element -1) are skipped.
std::vector<matcher::FlaggedElement> flagged_elements(const plan_diff_t& m);

// The as-built refinement (refined_* fields): per-segment offsets at both ends (non-finite ones skipped).
std::vector<matcher::SegmentOffset> refined_offsets(const plan_diff_t& m);

}  // namespace fploc::adapters
