// sensor_msgs/PointCloud2 of a spinning LiDAR -> fploc::Scan (the range image scan_t carries).
// Rows are rings sorted top beam first, with the ring's mean elevation as beam altitude; columns are
// azimuth bins in the Ouster convention (measurement id v at encoder angle 2*pi*(1 - v/W)), so the
// existing XYZ model (azimuth 0, beam offset 0, identity lidar_to_sensor) gives each point back to
// within half a column in azimuth. An organised cloud (height = rings) whose rows each keep their column to within a
// column of a fixed shift maps one point to one pixel: its columns are taken, the ring's mean azimuth offset from
// them is the ring's beam azimuth (no collision where its azimuths straddle a column edge). Recognised fields (Ouster, Velodyne, Hesai, Robosense, Livox drivers):
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
  // points = kept + no_return + collisions. no_return = zero_range + not_finite + too_far: points without a return
  // (the driver's x = y = z = 0, range < 1 mm), with a NaN/inf coordinate, or beyond 2000 m. A collision is a point
  // whose pixel of the range image (ring, column) another point already holds: the nearer of the two is kept.
  uint64_t points = 0, kept = 0, no_return = 0, collisions = 0;
  uint64_t zero_range = 0, not_finite = 0, too_far = 0;
  std::string ring_source;     // "field 'ring'" or "elevation"
  // "organised" (an organised cloud, one ring per row: each point's column in the cloud is its column in the image,
  // shifted per ring; the ring's mean azimuth offset from its column becomes its beam azimuth) or "azimuth" (the
  // column from the point's azimuth).
  std::string column_source;
  // Of an organised cloud: points binned by azimuth (off their ring's row, more than a column off the ring's shift,
  // or of a ring binned by azimuth whole), such rings (no row of their own, most points stray), and points whose ring
  // value has no row of its own, taken as points of their row's ring.
  uint64_t stray_points = 0;
  int azimuth_rings = 0;
  uint64_t relabelled_points = 0;
  std::string time_source;     // "field 't'" ... or "header stamp"
  double max_azimuth_error_deg = 0;  // worst |point azimuth - its pixel's azimuth in the scan's beam model|
};

// Returns false with *err on a cloud it cannot turn into a range image (no x/y/z, bad sizes, ...).
bool cloud_to_scan(const PointCloud2& cloud, const CloudOptions& opt, Scan& out, CloudStats* stats, std::string* err);

}  // namespace fploc::rec
