#include "fploc/config/perception.h"

namespace fploc::config {

seg::SegmenterConfig config_of(const SegmenterOptions& o) {
  seg::SegmenterConfig c;
  if (o.seed_rings() > 0) c.seed_rings = o.seed_rings();
  if (o.max_tilt_deg() > 0) c.max_tilt_deg = o.max_tilt_deg();
  if (o.wall_margin_m() > 0) c.wall_margin_m = o.wall_margin_m();
  c.use_imu_prior = o.use_imu_prior();
  c.deskew_gyro = !o.no_gyro_deskew();
  c.imu_attitude = !o.no_imu_attitude();
  if (o.ceiling_height_m() > 0) c.ceiling_height_m = o.ceiling_height_m();
  if (o.min_range_m() > 0) c.min_range_m = o.min_range_m();
  if (o.inlier_threshold_m() > 0) c.inlier_threshold_m = o.inlier_threshold_m();
  if (o.min_plane_inliers() > 0) c.min_plane_inliers = o.min_plane_inliers();
  if (o.irls_iterations() > 0) c.irls_iterations = o.irls_iterations();
  if (o.seed_triplets() > 0) c.seed_triplets = o.seed_triplets();
  return c;
}

feat::FeatureConfig config_of(const FeatureOptions& o) {
  feat::FeatureConfig c;
  if (o.sectors() > 0) c.sectors = o.sectors();
  if (o.max_corners_per_sector() > 0) c.max_corners_per_sector = o.max_corners_per_sector();
  if (o.max_surfaces_per_sector() > 0) c.max_surfaces_per_sector = o.max_surfaces_per_sector();
  if (o.corner_threshold() > 0) c.corner_threshold = o.corner_threshold();
  if (o.surface_threshold() > 0) c.surface_threshold = o.surface_threshold();
  if (o.max_range_m() > 0) c.max_range_m = o.max_range_m();
  if (o.min_range_m() > 0) c.min_range_m = o.min_range_m();
  if (o.half_window() > 0) c.half_window = o.half_window();
  if (o.min_group_points() > 0) c.min_group_points = o.min_group_points();
  if (o.line_max_rms_m() > 0) c.line_max_rms_m = o.line_max_rms_m();
  return c;
}

}  // namespace fploc::config
