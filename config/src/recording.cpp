#include "fploc/config/recording.h"

#include "fploc/config/check.h"

namespace fploc::config {

rec::CloudOptions config_of(const CloudToScanOptions& o) {
  rec::CloudOptions c;
  given(o.rings(), "cloud_to_scan", "rings");  // 0: derived from the cloud
  given(o.columns(), "cloud_to_scan", "columns");
  c.rings = o.rings();
  c.columns = o.columns();
  if (given(o.gap_deg(), "cloud_to_scan", "gap_deg")) c.gap_deg = o.gap_deg();
  return c;
}

}  // namespace fploc::config
