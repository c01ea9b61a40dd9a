// Options (proto/options/plandiff.proto) -> plan-change detection's settings (defaults: plandiff::Options' own;
// zero in the options = the default). fploc-plan-diff and `fploc map diff` both map them here.
#pragma once
#include "fploc/plandiff/plan_diff.h"
#include "options/plandiff.pb.h"

namespace fploc::config {

struct PlanDiffSettings {
  plandiff::Options diff;
  double publish_hz = 1;  // FPLOC_PLAN_DIFF rate in sensor time
  double frame_hz = 0;    // scans used per second of sensor time (0 = every scan)
};

// Throws OptionError naming the option for a negative value.
PlanDiffSettings config_of(const PlanDiffOptions& o);

}  // namespace fploc::config
