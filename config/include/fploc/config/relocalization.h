// Options (proto/options/relocalization.proto) -> RelocalizerConfig (defaults: the Config struct's).
#pragma once
#include "fploc/relocalization/relocalizer.h"
#include "fploc/relocalization/schedule.h"
#include "options/relocalization.pb.h"

namespace fploc::config {

// The search's settings.
reloc::RelocalizerConfig config_of(const RelocalizerOptions& o);

// region_radius_m, global_after_s, min_interval_s: when fploc-relocalizer searches (0 = the default).
reloc::Schedule schedule_of(const RelocalizerOptions& o);

}  // namespace fploc::config
