// CARMEN log files (the Radish 2D laser logs): a parser of the records fploc uses, and an occupancy grid
// built from scans at known poses (the mapping half of `fploc bench real`). Transport-free.
//
// Records (one per line, whitespace-separated; '#' lines are comments):
//   FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
//     front laser: n ranges [m] over 180 degrees from -90 degrees (x forward, counter-clockwise); x y theta the
//     laser's pose (in the "corrected" Radish logs the SLAM-corrected pose, the usual reference; the
//     odom_* columns there repeat it); ranges at the scanner's maximum are "no return".
//   ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp   wheel odometry
// Everything else (PARAM, NEFF, RLASER, SYNC, TRUEPOS, ...) is skipped and counted.
// Errors: std::runtime_error "SOURCE:LINE: RECORD: field K (NAME): what".
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace fploc::carmen {

struct Pose2d {
  double x = 0, y = 0, theta = 0;
};

struct LaserRecord {
  size_t line = 0;
  std::vector<float> ranges;
  Pose2d pose;          // x y theta (corrected in the Radish logs)
  Pose2d odom;          // odom_x odom_y odom_theta
  double ipc_timestamp = 0, logger_timestamp = 0;
  // The wheel odometry at this scan (valid when have_wheel_odom): a continuous dead-reckoned chain whose
  // increment from the previous scan is the odometry's own motion between the two scans, i.e. between the last
  // ODOM record before the previous scan and the last ODOM record before this one, unless the odometry was
  // re-anchored in between (see Log::odom_reanchors): then from the re-anchoring record.
  Pose2d wheel_odom;
  bool have_wheel_odom = false;
};

struct OdomRecord {
  size_t line = 0;
  Pose2d pose;
  double tv = 0, rv = 0, accel = 0, ipc_timestamp = 0;
};

struct Log {
  std::vector<LaserRecord> scans;
  std::vector<OdomRecord> odom;
  std::map<std::string, size_t> skipped;  // record type -> count
  // Re-anchorings of the ODOM stream: an ODOM record right after a FLASER that repeats the FLASER's (corrected)
  // pose. The Radish "corrected" logs restart the odometry chain at every scan this way (the records after it
  // integrate the wheels from the corrected pose), so the last ODOM record before a scan lies in a chain
  // started at the previous scan's reference pose; differencing those records between scans would mix the
  // reference's increment of the previous step into the odometry. The chain's own increment (from the anchor)
  // is the wheels' motion alone. Anchor records are not part of `odom`.
  size_t odom_reanchors = 0;
};

// Parses a whole log (text, already decompressed). With `damage`, a bad record ends the log there instead of
// throwing (when records came before it): *damage says which and why, and the records before it are returned.
Log parse_log(const std::string& text, const std::string& source, std::string* damage = nullptr);
// Reads a file; .gz is decompressed with zlib. With `damage`, compressed data that are cut or corrupt end the text
// there instead of throwing: *damage says where, and the text decompressed before it is returned.
std::string read_maybe_gz(const std::string& path, std::string* damage = nullptr);

// Beam geometry of a FLASER with n beams over 180 degrees: angle_i = -pi/2 + i * increment, increment
// pi/n for even n (180: 1 degree, 360: 0.5 degree) and pi/(n-1) for odd n (181, 361: both ends included).
double beam_increment(size_t n);
// The scanner's maximum ("no return") range: ranges >= it are no return. The largest range in the log when
// it repeats often (>= 1 % of beams at exactly that value: 81.91 m csail, 50 m ...), else +inf.
float no_return_range(const Log& log);

// Scan times [s], strictly increasing: the ipc timestamps when they are (to 1 ms) increasing and resolve
// the scans; out-of-order ones are moved 1 ms after their predecessor. When the log's timestamps do not
// resolve the scans (fewer distinct values than half the scans, e.g. csail's 6 significant digits), the
// scans are spaced evenly over the log's duration (or 1 s apart); `note` says which.
std::vector<double> scan_times(const Log& log, std::string* note = nullptr);

// Occupancy grid from scans at known laser poses: every beam marks the cells it crosses free and its end
// cell hit (no-return beams mark free up to max_free_m). A cell is occupied when hits >= min_hits and
// hits >= occupied_ratio * (hits + misses), free when it was crossed and is not occupied, else unknown.
// Defaults: the map of `fploc bench real` (1 hit, 10 %, 0.1 m clearance). With 2 / 25 % / 0, beams grazing a
// wall erased it (docs/notes/real2d.md): an intel replay through graphs/lidar2d.pbtxt scored 20 cm ATE on that
// map against 6.7 cm on this one.
struct GridConfig {
  double resolution = 0.05;
  double margin_m = 1.0;
  double occupied_ratio = 0.1;
  int min_hits = 1;
  double max_free_m = 20.0;
  float no_return = 1e30f;
  double min_range_m = 0.05;
  double hit_clearance_m = 0.1;  // a beam marks no cell within this of its hit free
};
struct Grid {
  int width = 0, height = 0;
  double resolution = 0, origin_x = 0, origin_y = 0;
  std::vector<int8_t> cells;  // row 0 = bottom; -1 unknown, 0 free, 100 occupied
};
Grid build_grid(const std::vector<const LaserRecord*>& scans, const GridConfig& cfg);
// map_server files: DIR/NAME.pgm (occupied 0, free 254, unknown 205) + DIR/NAME.yaml (trinary).
void write_map_server(const Grid& g, const std::string& dir, const std::string& name);

}  // namespace fploc::carmen
