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

}  // namespace fploc::config
