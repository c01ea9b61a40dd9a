// The AMCL baseline's settings around the filter (modules/amcl/amcl.h has the filter's own Config): how
// the features become a planar scan, how wide the initial cloud is, and how the odometry is guarded and
// (for the benches) simulated. Defaults are written here once; config/ maps the graph's AmclOptions onto
// these structs and config_defaults_test checks the proto comments against them.
#pragma once

#include "fploc/amcl/amcl.h"
#include "fploc/amcl/odometry.h"

namespace fploc::amcl {

// Features -> `bins` beams over 360 deg (nearest feature per beam), as points_to_scan does.
struct ScanConversion {
  int bins = 360;             // 1 deg, a common 2D LiDAR resolution
  double range_min_m = 0.0;
  double range_max_m = 100.0;
};

// The initial particle cloud around a given pose (RViz's "2D Pose Estimate" spread).
struct InitialSpread {
  double std_xy_m = 0.5;
  double std_yaw_deg = 15.0;
};

enum class OdometrySource { kPose, kSimulatedWheel };

struct Settings {
  Config filter;
  ScanConversion scan;
  InitialSpread initial;
  OdometrySource odometry = OdometrySource::kPose;
  WheelOdometryConfig wheel;   // used with kSimulatedWheel
  OdometryGuardConfig guard;
  // A scan without an odometry sample at its utime gets the interpolation of the two samples around it when
  // they are at most this far apart (odometry at its own rate); otherwise it is dropped with an error.
  double odometry_max_gap_s = 0.25;
};

}  // namespace fploc::amcl
