// The scans [first, end) of a CARMEN log that fploc-real-floor and fploc-real-track fit to a map, and the
// longest range a beam of them is used to (the log's no-return range when it has one, else max_range_m).
#pragma once
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fploc/carmen/carmen.h"
#include "fploc/core/pose.h"

namespace fploc::bench_real {

struct LogScans {
  carmen::Log log;
  size_t first = 0, end = 0;  // end exclusive, within the log
  double max_range_m = 0;
};

// end 0 (or past the log): to the log's end. Throws naming the options when the range selects no scans.
inline LogScans load_log_scans(const std::string& path, size_t first, size_t end, double max_range_m) {
  LogScans s;
  s.log = carmen::parse_log(carmen::read_maybe_gz(path), path);
  s.first = first;
  s.end = end == 0 || end > s.log.scans.size() ? s.log.scans.size() : end;
  if (s.first >= s.end) throw std::runtime_error("--first-scan/--end-scan select no scans");
  const float no_return = carmen::no_return_range(s.log);
  s.max_range_m = std::isfinite(no_return) ? std::min<double>(max_range_m, no_return) : max_range_m;
  return s;
}

// The bench's start for scan `first`: its reference pose ("ref"), or 1 m off along the heading's left diagonal
// and 10 degrees ("off").
inline Pose2 start_pose(const carmen::Log& log, size_t first, const std::string& start) {
  const auto& s0 = log.scans[first].pose;
  Pose2 p0{s0.x, s0.y, s0.theta};
  if (start == "off") p0 = {p0.x + std::cos(p0.yaw + M_PI / 4), p0.y + std::sin(p0.yaw + M_PI / 4), p0.yaw + 10 * M_PI / 180};
  return p0;
}

}  // namespace fploc::bench_real
