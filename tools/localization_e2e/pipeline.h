// Library-level end-to-end run (no LCM): simulator -> ring segmenter -> features -> the Localizer
// (matcher + windowed optimizer, fploc::localizer) in a loop, plus the no-plan odometry baseline on the
// same features. Used by the e2e test (tests/localizer) and by the localization_e2e tool (numbers in
// docs/notes/localization.md).
#pragma once
#include <string>

#include "fploc/core/pose.h"
#include "fploc/floorplan/plan.h"

namespace fploc::e2e {

struct Options {
  std::string scenario = "room-small-loop-medium";
  uint64_t seed = 1;
  int max_frames = 0;            // 0 = whole sequence
  std::string lookup = "annf-exact";
  bool imu = true;
  std::string shared_dir;        // beams from ../shared when present
  double gt_offset_s = 0;        // ground truth at the frame's time stamp (scan start) + this
  int window = 10;
  double alpha = 1.1, beta = 0.9;
  bool clutter = true;
  double range_noise_m = -1;      // < 0: the simulator's default
  double wall_clutter = 0;        // fraction of the walls behind cabinets (simulator option)
  double drop_fraction = 0;      // drop this fraction of scans (deterministic)
  double keyframe_distance_m = 0.1;
  int matcher_points = 800, optimizer_points = 800;
  bool body_frame_velocity = false;
  double relook_m = -1;          // optimizer's re-look-up distance (< 0: its default)
  double init_dx = 0, init_dy = 0, init_dyaw = 0;  // error of the initial pose
  double init_search_m = 0;      // matcher's first-frame search radius (0 = its default)
  bool gt_gravity = false;       // diagnostic: features projected with the true roll/pitch (mid-sweep)
  std::string frames_csv;        // per-frame diagnostics (status, fit, errors against ground truth) to this file
};

struct Result {
  int frames = 0, ok_frames = 0, lost_frames = 0;
  double length_m = 0, avg_speed = 0, max_speed = 0;
  double ate_sfr = 0, rpe_sfr = 0, ate_wo = 0, rpe_wo = 0, ate_odo = 0, rpe_odo = 0;  // rmse ATE, mean RPE (1 s), 3D
  // The same in the horizontal plane only (x, y: what the matcher and optimizer estimate; z is the segmenter's).
  double ate_sfr_xy = 0, rpe_sfr_xy = 0, ate_wo_xy = 0, rpe_wo_xy = 0, ate_odo_xy = 0, rpe_odo_xy = 0;
  double us_segment = 0, us_features = 0, us_matcher = 0, us_optimizer = 0, us_odometry = 0;  // per scan
  double features_per_scan = 0;
  Trajectory gt, sfr, wo, odo;
};

Result run(const FloorPlan& plan, const Options& o);

}  // namespace fploc::e2e
