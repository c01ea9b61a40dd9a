// 2D LiDAR mode: one planar laser scan (sensor_msgs/LaserScan in fploc's terms) -> the 2D wall features the
// matcher, optimizer, odometry and AMCL consume (fploc::FeatureFrame, the payload of features_t).
//
// Beam i is at angle_min + i * angle_increment [rad] (x forward, counter-clockwise) and was measured
// i * time_increment [s] after utime. A beam is a return when its range is finite and inside
// [max(range_min, cfg.min_range_m), min(range_max, cfg.max_range_m)]; everything else is dropped. The
// returns are one ring of "wall points" (column = beam index, so gaps break LOAM's neighbourhoods) and go
// through the same LOAM selection as the 3D pipeline (modules/features: smoothness over +-half_window beams,
// occlusion and parallel-beam rules, per-sector corner/surface limits, PCA line groups of the surface
// points). For a 2D scanner that is all of LOAM that applies: there is no ground or ceiling, and the
// scan already lies in the plane. roll/pitch come from the caller (an IMU; 0 on a level robot), z is fixed.
// Transport-free; nodes/laser2d wraps it.
#pragma once
#include <cstdint>
#include <vector>

#include "fploc/features/features.h"
#include "fploc/segmentation/segmenter.h"

namespace fploc::laser2d {

struct PlanarScan {
  int64_t utime = 0, seq = 0;
  float angle_min = 0, angle_increment = 0, time_increment = 0;
  float range_min = 0, range_max = 0;
  std::vector<float> ranges;
};

struct Laser2dConfig {
  double min_range_m = 0.05;     // a beam closer than this (or than the scan's range_min) is no return
  double max_range_m = 60.0;     // farther (or beyond the scan's range_max) is no return
  double mount_x_m = 0, mount_y_m = 0, mount_yaw_rad = 0;  // laser in the robot frame (the pose estimated)
  bool upside_down = false;      // mounted upside down: angles mirror
  double z_m = 0;                // the laser's (fixed) height, passed on as z
  feat::FeatureConfig features = default_features();
  // A planar scan has a few hundred beams, LOAM keeps a few dozen of them (measured on the Radish logs:
  // 30-60), too few to tell apart the parallel walls of an office: every other return is passed on too, as
  // an unclassified surface point (group -1), after LOAM's picks. The matcher's point budget (800) holds them.
  bool all_returns = true;
  // LOAM limits for one ring of a few hundred beams: more surface points per sector than for a 64-ring scan.
  static feat::FeatureConfig default_features();
};

struct Laser2dStats {
  int beams = 0, returns = 0, dropped_non_finite = 0, dropped_range = 0;
};

class Laser2dFeatures {
 public:
  explicit Laser2dFeatures(Laser2dConfig cfg = {});
  // roll/pitch [rad] (R = Ry(pitch) Rx(roll)); sigma: 1-sigma of roll/pitch [rad]. Status kBadInput when the
  // scan's geometry is not usable (non-finite or zero angle_increment, no beams), kFewFeatures when LOAM
  // selects fewer than 30 points.
  const FeatureFrame& process(const PlanarScan& s, double roll = 0, double pitch = 0, double roll_pitch_sigma = 0.01);
  const Laser2dStats& stats() const { return stats_; }
  const Laser2dConfig& config() const { return cfg_; }
  // The returns of the last scan in the robot frame (diagnostics, tests).
  const seg::WallPoints& points() const { return seg_.wall; }

 private:
  Laser2dConfig cfg_;
  feat::FeatureExtractor fx_;
  FeatureFrame out_;
  std::vector<uint8_t> used_;
  seg::Segmentation seg_;
  Laser2dStats stats_;
};

}  // namespace fploc::laser2d
