#include "fploc/config/perception.h"

#include "fploc/config/check.h"

namespace fploc::config {

seg::SegmenterConfig config_of(const SegmenterOptions& o) {
  seg::SegmenterConfig c;
  if (given(o.seed_rings(), "segmenter", "seed_rings")) c.seed_rings = o.seed_rings();
  if (given(o.max_tilt_deg(), "segmenter", "max_tilt_deg")) c.max_tilt_deg = o.max_tilt_deg();
  if (given(o.wall_margin_m(), "segmenter", "wall_margin_m")) c.wall_margin_m = o.wall_margin_m();
  c.use_imu_prior = o.use_imu_prior();
  c.deskew_gyro = !o.no_gyro_deskew();
  c.imu_attitude = !o.no_imu_attitude();
  if (given(o.ceiling_height_m(), "segmenter", "ceiling_height_m")) c.ceiling_height_m = o.ceiling_height_m();
  if (given(o.min_range_m(), "segmenter", "min_range_m")) c.min_range_m = o.min_range_m();
  if (given(o.inlier_threshold_m(), "segmenter", "inlier_threshold_m")) c.inlier_threshold_m = o.inlier_threshold_m();
  if (given(o.min_plane_inliers(), "segmenter", "min_plane_inliers")) c.min_plane_inliers = o.min_plane_inliers();
  if (given(o.irls_iterations(), "segmenter", "irls_iterations")) c.irls_iterations = o.irls_iterations();
  if (given(o.seed_triplets(), "segmenter", "seed_triplets")) c.seed_triplets = o.seed_triplets();
  given(o.ransac_max_iterations(), "segmenter", "ransac_max_iterations");  // fploc-segmenter-ransac's (200)
  return c;
}

feat::FeatureConfig config_of(const FeatureOptions& o) {
  feat::FeatureConfig c;
  if (given(o.sectors(), "features", "sectors")) c.sectors = o.sectors();
  if (given(o.max_corners_per_sector(), "features", "max_corners_per_sector")) c.max_corners_per_sector = o.max_corners_per_sector();
  if (given(o.max_surfaces_per_sector(), "features", "max_surfaces_per_sector")) c.max_surfaces_per_sector = o.max_surfaces_per_sector();
  if (given(o.corner_threshold(), "features", "corner_threshold")) c.corner_threshold = o.corner_threshold();
  if (given(o.surface_threshold(), "features", "surface_threshold")) c.surface_threshold = o.surface_threshold();
  if (given(o.max_range_m(), "features", "max_range_m")) c.max_range_m = o.max_range_m();
  if (given(o.min_range_m(), "features", "min_range_m")) c.min_range_m = o.min_range_m();
  if (given(o.half_window(), "features", "half_window")) c.half_window = o.half_window();
  if (given(o.min_group_points(), "features", "min_group_points")) c.min_group_points = o.min_group_points();
  if (given(o.line_max_rms_m(), "features", "line_max_rms_m")) c.line_max_rms_m = o.line_max_rms_m();
  if (given(o.column_front_m(), "features", "column_front_m")) c.column_front_m = o.column_front_m();
  if (given(o.high_band_m(), "features", "high_band_m")) c.high_band_m = o.high_band_m();
  if (given(o.high_min_points(), "features", "high_min_points")) c.high_min_points = o.high_min_points();
  if (given(o.high_same_surface_m(), "features", "high_same_surface_m")) c.high_same_surface_m = o.high_same_surface_m();
  c.high_keep_unseen = o.high_keep_unseen();
  return c;
}

}  // namespace fploc::config
