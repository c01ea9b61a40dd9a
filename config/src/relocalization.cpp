#include "fploc/config/relocalization.h"

#include <algorithm>

#include "fploc/config/check.h"

namespace fploc::config {

reloc::RelocalizerConfig config_of(const RelocalizerOptions& o) {
  reloc::RelocalizerConfig c;
  if (given(o.grid_m(), "relocalizer", "grid_m")) c.grid_m = o.grid_m();
  if (given(o.yaw_step_deg(), "relocalizer", "yaw_step_deg")) c.yaw_step_deg = o.yaw_step_deg();
  if (given(o.min_inlier_ratio(), "relocalizer", "min_inlier_ratio")) c.min_inlier_ratio = o.min_inlier_ratio();
  if (given(o.min_evidence(), "relocalizer", "min_evidence")) c.min_evidence = o.min_evidence();
  return c;
}

reloc::Schedule schedule_of(const RelocalizerOptions& o) {
  reloc::Schedule s;
  if (given(o.region_radius_m(), "relocalizer", "region_radius_m")) s.region_radius_m = o.region_radius_m();
  if (given(o.global_after_s(), "relocalizer", "global_after_s")) s.global_after_s = o.global_after_s();
  if (given(o.min_interval_s(), "relocalizer", "min_interval_s")) s.min_interval_s = o.min_interval_s();
  if (o.max_speed_mps() != 0) s.max_speed_mps = std::max(0.0, o.max_speed_mps());
  if (given(o.speed_margin_m(), "relocalizer", "speed_margin_m")) s.speed_margin_m = o.speed_margin_m();
  return s;
}

}  // namespace fploc::config
