// Where each planar laser of a recording sits on the robot, from tf: the transform robot frame -> the laser's
// frame (its scans' header.frame_id) over the recording. What the 2D mode needs from it: the mount in the plane
// (x, y, yaw; upside down) for laser2d / grid2d, and whether the scan plane is level and stays so (a laser on a
// tilting or nodding unit sweeps the room in 3D: not a planar scanner).
#pragma once
#include <string>

#include "tf_tree.h"

namespace fploc::import {

struct LaserMount {
  std::string topic, frame, base;
  bool found = false;  // tf connects base and frame
  std::string why;     // when not found
  double x_m = 0, y_m = 0, z_m = 0, yaw_deg = 0;  // the mount's mean over time (yaw: the laser's x axis in the base plane)
  bool upside_down = false;                        // the scan plane's normal points down (on time average)
  double tilt_min_deg = 0, tilt_max_deg = 0;       // the scan plane's angle to the base plane over the recording
  static constexpr double kLevelDeg = 3;           // a scan plane within this of the base plane is level
  bool level() const { return found && tilt_max_deg <= kLevelDeg; }
  // "level on base_link at x 0.20 y 0.00 z 0.30 m, yaw 180.0 deg" / "tilts 0.0-57.4 deg ... (a tilting laser)"
  std::string describe() const;
};

// The robot frame the mounts are given in: `preferred` when tf has it, else base_link, else base_footprint; ""
// when none is there.
std::string robot_frame(const TfTree& tree, const std::string& preferred);

// The mount of the laser whose scans are in `frame`, over every sample of the tf edges between it and `base`
// (tree sorted): the tilt's range over the samples, the mean weighted by time (each sample half the time to its
// neighbours), from the first time every edge has a sample to the last sample.
LaserMount laser_mount(const TfTree& tree, const std::string& base, const std::string& topic, const std::string& frame);

}  // namespace fploc::import
