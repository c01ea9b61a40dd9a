#include "fploc/segmentation/scan_imu_sync.h"

#include <algorithm>

#include "segmenter_constants.h"

namespace fploc::seg {

int64_t ScanImuSync::sweep_end(const Scan& scan) {
  const bool cvalid = scan.column_valid.size() == scan.column_utime.size();
  int64_t end = scan.utime;
  for (size_t c = 0; c < scan.column_utime.size(); ++c)
    if (scan.column_utime[c] != 0 && (!cvalid || scan.column_valid[c])) end = std::max(end, scan.column_utime[c]);
  return end;
}

bool ScanImuSync::ready(int64_t start_utime, int64_t end_utime) const {
  if (last_imu_ <= 0 || last_imu_ < start_utime - live_window_us_) return true;
  return last_imu_ >= end_utime - k::kGyroEdgeUs;
}

}  // namespace fploc::seg
