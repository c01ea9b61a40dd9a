// Options (proto/options/relocalization.proto) -> RelocalizerConfig (defaults: the Config struct's).
#pragma once
#include "fploc/relocalization/relocalizer.h"
#include "options/relocalization.pb.h"

namespace fploc::config {

// The search's settings; region_radius_m, global_after_s and min_interval_s are fploc-relocalizer's
// scheduling (when to search), not the search's.
reloc::RelocalizerConfig config_of(const RelocalizerOptions& o);

}  // namespace fploc::config
