#include "fploc/config/relocalization.h"

namespace fploc::config {

reloc::RelocalizerConfig config_of(const RelocalizerOptions& o) {
  reloc::RelocalizerConfig c;
  if (o.grid_m() > 0) c.grid_m = o.grid_m();
  if (o.yaw_step_deg() > 0) c.yaw_step_deg = o.yaw_step_deg();
  if (o.min_inlier_ratio() > 0) c.min_inlier_ratio = o.min_inlier_ratio();
  if (o.min_evidence() > 0) c.min_evidence = o.min_evidence();
  return c;
}

reloc::Schedule schedule_of(const RelocalizerOptions& o) {
  reloc::Schedule s;
  if (o.region_radius_m() > 0) s.region_radius_m = o.region_radius_m();
  if (o.global_after_s() > 0) s.global_after_s = o.global_after_s();
  if (o.min_interval_s() > 0) s.min_interval_s = o.min_interval_s();
  return s;
}

}  // namespace fploc::config
