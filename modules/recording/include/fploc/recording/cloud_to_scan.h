// sensor_msgs/PointCloud2 of a spinning LiDAR -> fploc::Scan (the range image scan_t carries).
// Rows are rings sorted top beam first, with the ring's mean elevation as beam altitude; columns are
// azimuth bins in the Ouster convention (measurement id v at encoder angle 2*pi*(1 - v/W)), so the
// existing XYZ model (azimuth 0, beam offset 0, identity lidar_to_sensor) gives each point back to
// within half a column in azimuth. Recognised fields (Ouster, Velodyne, Hesai, Robosense, Livox drivers):
//   x y z (FLOAT32/64), intensity|reflectivity|signal, ring|channel|line (ring index),
//   t (UINT32 ns from the header stamp: Ouster), time (FLOAT32 s from the stamp: Velodyne),
//   timestamp (FLOAT64: absolute s for Hesai/Robosense, absolute ns when > 1e15 for Livox),
//   offset_time (UINT32 ns: Livox custom).
// Without a ring field rings come from elevation: the (rings - 1) largest gaps of the sorted point
// elevations when the ring count is given, else every gap > gap_deg.
#pragma once
#include <cstdint>
#include <string>

#include "fploc/core/scan.h"
#include "fploc/recording/ros_msgs.h"

namespace fploc::rec {

struct CloudOptions {
  int rings = 0;          // 0: from the ring field, else from elevation gaps
  int columns = 0;        // 0: the organised width, else the most points of any ring
  double gap_deg = 0.25;  // elevation gap that separates rings (no ring field, rings == 0)
};

struct CloudStats {
  uint64_t points = 0, kept = 0, no_return = 0, collisions = 0;
  std::string ring_source;     // "field 'ring'" or "elevation"
  std::string time_source;     // "field 't'" ... or "header stamp"
  double max_azimuth_error_deg = 0;  // worst |point azimuth - its column's azimuth|
};

// Returns false with *err on a cloud it cannot turn into a range image (no x/y/z, bad sizes, ...).
bool cloud_to_scan(const PointCloud2& cloud, const CloudOptions& opt, Scan& out, CloudStats* stats, std::string* err);

}  // namespace fploc::rec
