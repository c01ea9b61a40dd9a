#include "fploc/config/recording.h"

namespace fploc::config {

rec::CloudOptions config_of(const CloudToScanOptions& o) {
  rec::CloudOptions c;
  c.rings = o.rings();
  c.columns = o.columns();
  if (o.gap_deg() > 0) c.gap_deg = o.gap_deg();
  return c;
}

}  // namespace fploc::config
