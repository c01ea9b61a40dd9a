// When fploc-relocalizer searches (the search itself is Relocalizer): after a loss, first around the last
// good pose, then, lost for longer (or never localized), over the whole plan; never more often than
// min_interval_s of sensor time. Defaults written once here (config_defaults_test checks the proto).
#pragma once

#include <algorithm>

namespace fploc::reloc {

struct Schedule {
  double region_radius_m = 3.0;  // the local search's radius around the last good pose
  double global_after_s = 2.0;   // lost longer than this: search the whole plan
  double min_interval_s = 0.5;   // between two searches, in sensor time
  // The local search's radius is also no more than the platform can have driven since the last good pose (its
  // speed at most, as the matcher's motion model, times the time since), plus speed_margin_m (that pose's own error
  // and the search's grid step); 0 = region_radius_m alone.
  double max_speed_mps = 2.0;
  double speed_margin_m = 0.5;
};

// The local search's radius `since_ok_s` seconds after the last good pose.
inline double local_radius_m(const Schedule& s, double since_ok_s) {
  if (!(s.max_speed_mps > 0)) return s.region_radius_m;
  return std::min(s.region_radius_m, s.speed_margin_m + s.max_speed_mps * std::max(0.0, since_ok_s));
}

}  // namespace fploc::reloc
