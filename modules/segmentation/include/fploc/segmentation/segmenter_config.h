// Options of the ceiling/ground segmenter (paper section IV-A); defaults written once, here.
#pragma once

namespace fploc::seg {

struct SegmenterConfig {
  int seed_rings = 4;              // K_r: top (bottom) rings giving the seed points
  int seed_sectors = 64;           // azimuth sectors per seed ring (one max-range candidate each)
  double seed_fraction = 0.25;     // keep this fraction of the sector maxima (largest ranges) per ring
  int seed_triplets = 40;          // planes through seed triplets also tried as the IRLS start
  double max_tilt_deg = 10.0;      // reject planes tilted more than this from the gravity prior
  double wall_margin_m = 0.10;     // points closer than this to ceiling/floor are not wall points
  double ceiling_height_m = 0.0;   // known floor-to-ceiling height; 0 = estimated (ceiling + ground fits)
  bool use_imu_prior = false;      // IMU gravity as initial direction, tilt gate and fallback
  bool deskew_gyro = true;
  // Roll/pitch against gravity with the IMU (gravity_fusion.h) when gyro samples arrive: slopes (ramps) from the
  // planes' disagreement with the gyro/accelerometer, gyro prediction without planes, and roll/pitch moved
  // from mid-sweep to the scan's time (jolts). Level floors: the planes' attitude unchanged.
  bool imu_attitude = true;         // rotate returns to mid-sweep with the gyro rate (when gyro samples arrive)
  // With the IMU, the ground at a kink (ground_kink.cpp: the returns near the ground split into sectors, each
  // fitted, the surface under the robot found) runs on every scan while a second surface or a ring fit off the
  // followed surface is in view. While one surface is followed steadily (the last split found it alone, the ring
  // fit on it and the ceiling giving the attitude, and this scan's ring fit still on it as the gyro carries it,
  // with no sweep to correct) the split, whose result would be the ring fit as it is, is skipped on up to this
  // many scans minus one before it runs again (1: it runs on every scan).
  // 8: a second surface that comes into view without moving the ring fit is split off at most 0.7 s (10 Hz) later;
  // the ring fit itself leaving the followed surface (a kink under the robot) ends the skipping on that scan.
  int kink_recheck_scans = 8;
  // The recheck at the end of those scans (the surface still followed steadily) runs on every
  // kink_recheck_stride-th of the returns near the ring fit, its sectors' minimum counts divided by it; when it
  // finds the one surface again (the planes as they are) that stands, else it is undone and the split runs on
  // every return, which decides every other outcome (1: every return always).
  int kink_recheck_stride = 2;
  // The plane fits' start (ring_plane_fit.cpp): the seeds, the seed regression, the seed triplets and last frame's
  // plane scored on a subsample, the best refined, then last frame's plane refined too. While a plane is followed
  // steadily (the last search's start was last frame's plane, or the refinement from it joined the best start's)
  // the next fits of that plane refine last frame's plane alone, on up to this many scans minus one in a row
  // before the search runs again; a refinement that loses support, or moves the plane more than a step a
  // search would be needed for, ends it on that scan (1: the search on every scan).
  int start_recheck_scans = 8;
  double min_range_m = 0.4;        // ignore returns closer than this (platform, tripod)
  double max_range_m = 120.0;
  int min_plane_inliers = 200;     // fewer inliers -> plane not found
  double min_inlier_fraction = 0.02;  // of the upper (lower) half-ring returns (a corridor ceiling: ~3 %)
  double max_beyond_ratio = 0.25;     // reject a plane with more returns beyond it than this x inliers
  double inlier_threshold_m = 0.05;// inlier band for counting / rms
  int irls_iterations = 8;
  double irls_initial_scale_m = 0.2;  // first Tukey cut-off (4 x the 5 cm band that chose the start);
                                      // halves every iteration down to ~4.7 sigma
  int room_height_window = 51;     // frames in the running median of the floor-to-ceiling height
  // Height/attitude consistency (attitude_height.cpp): the ceiling's floor-to-ceiling height (ceiling +
  // ground distance) more than this off the area's height means the ceiling over the sensor is not the
  // area's (a sloped patch, a lamp, an atrium edge): z from the floor instead.
  double z_consistency_m = 0.03;
  // Ceiling and ground normals more than this apart: one of them is not level; the one agreeing with the
  // IMU (else the better-fitted one) gives roll/pitch.
  double attitude_consistency_deg = 0.3;
  // With the ceiling alone: z moving more than this from the last estimate in one scan is a ceiling step
  // (another area), not motion: z is predicted and the area height re-learned from the new ceiling.
  double z_jump_m = 0.05;
  // With a building's area ceilings: let the building turn a sloped ceiling's normal by its slope and decide
  // ceiling-vs-floor disagreements by which attitude fits the areas' heights (attitude_height.cpp). Off by
  // default: right on synthetic ramps (segmentation_area_height_test) but worse end to end on the simulated
  // building-areas and demo-building ramp runs (docs/notes/height.md); z from the areas' heights is always on.
  bool building_attitude = false;
  double tight_refit_sigmas = 2.5; // ceiling refit at this many robust sigmas (0 = off), see fit_plane
};

}  // namespace fploc::seg
