// When fploc-relocalizer searches (the search itself is Relocalizer): after a loss, first around the last
// good pose, then, lost for longer (or never localized), over the whole plan; never more often than
// min_interval_s of sensor time. Defaults written once here (config_defaults_test checks the proto).
#pragma once

namespace fploc::reloc {

struct Schedule {
  double region_radius_m = 3.0;  // the local search's radius around the last good pose
  double global_after_s = 2.0;   // lost longer than this: search the whole plan
  double min_interval_s = 0.5;   // between two searches, in sensor time
};

}  // namespace fploc::reloc
