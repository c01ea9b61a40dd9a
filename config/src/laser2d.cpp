#include "fploc/config/laser2d.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "fploc/config/check.h"

namespace fploc::config {

laser2d::Laser2dConfig config_of(const Laser2dOptions& o) {
  laser2d::Laser2dConfig c;
  if (given(o.min_range_m(), "laser2d", "min_range_m")) c.min_range_m = o.min_range_m();
  if (given(o.max_range_m(), "laser2d", "max_range_m")) c.max_range_m = o.max_range_m();
  c.mount_x_m = o.mount_x_m();
  c.mount_y_m = o.mount_y_m();
  c.mount_yaw_rad = o.mount_yaw_deg() * M_PI / 180;
  c.upside_down = o.upside_down();
  c.z_m = o.z_m();
  if (given(o.max_corners_per_sector(), "laser2d", "max_corners_per_sector"))
    c.features.max_corners_per_sector = o.max_corners_per_sector();
  if (given(o.max_surfaces_per_sector(), "laser2d", "max_surfaces_per_sector"))
    c.features.max_surfaces_per_sector = o.max_surfaces_per_sector();
  if (given(o.corner_threshold(), "laser2d", "corner_threshold")) c.features.corner_threshold = o.corner_threshold();
  if (given(o.surface_threshold(), "laser2d", "surface_threshold")) c.features.surface_threshold = o.surface_threshold();
  c.features.min_range_m = c.min_range_m;
  c.features.max_range_m = c.max_range_m;
  return c;
}

laser2d::GridLocalizerConfig config_of(const Grid2dOptions& o) {
  laser2d::GridLocalizerConfig c;
  constexpr double kRad = M_PI / 180;
  if (given(o.initial_sigma_xy_m(), "grid2d", "initial_sigma_xy_m")) c.initial_sigma_xy_m = o.initial_sigma_xy_m();
  if (given(o.initial_sigma_yaw_deg(), "grid2d", "initial_sigma_yaw_deg")) c.initial_sigma_yaw_rad = o.initial_sigma_yaw_deg() * kRad;
  if (given(o.min_range_m(), "grid2d", "min_range_m")) c.min_range_m = o.min_range_m();
  if (given(o.max_range_m(), "grid2d", "max_range_m")) c.max_range_m = o.max_range_m();
  if (given(o.min_inlier_ratio(), "grid2d", "min_inlier_ratio")) c.min_inlier_ratio = o.min_inlier_ratio();
  if (given(o.field_max_m(), "grid2d", "field_max_m")) c.field_max_m = o.field_max_m();
  if (given(o.min_inlier_ratio_near(), "grid2d", "min_inlier_ratio_near")) c.min_inlier_ratio_near = o.min_inlier_ratio_near();
  if (given(o.gate_sigmas(), "grid2d", "gate_sigmas")) c.gate_sigmas = o.gate_sigmas();
  if (given(o.sigma_xy_per_m(), "grid2d", "sigma_xy_per_m")) c.sigma_xy_per_m = o.sigma_xy_per_m();
  if (given(o.sigma_yaw_per_rad(), "grid2d", "sigma_yaw_per_rad")) c.sigma_yaw_per_rad = o.sigma_yaw_per_rad();
  if (given(o.prior_weight_sigmas(), "grid2d", "prior_weight_sigmas")) c.prior_weight_sigmas = o.prior_weight_sigmas();
  if (o.has_laser_odometry()) c.laser_odometry = o.laser_odometry();
  if (given(o.laser_map_scans(), "grid2d", "laser_map_scans")) c.laser.map_scans = o.laser_map_scans();
  if (o.confirm_within_sigmas() != 0) c.confirm_within_sigmas = o.confirm_within_sigmas();
  if (o.far_confirm_travel_m() != 0) c.far_confirm_travel_m = o.far_confirm_travel_m();
  if (!o.fit_loss().empty()) {
    const auto loss = laser2d::fit_loss_from_name(o.fit_loss());
    if (!loss)
      throw OptionError("grid2d", "fit_loss", "unknown loss '" + o.fit_loss() +
                                                       "' (use \"huber\", \"cauchy\" or \"tukey\")");
    c.fit_loss = *loss;
  }
  if (given(o.huber_m(), "grid2d", "huber_m")) c.huber_m = o.huber_m();
  if (given(o.huber_first_above_sigma_m(), "grid2d", "huber_first_above_sigma_m")) c.huber_first_above_sigma_m = o.huber_first_above_sigma_m();
  if (o.laser_conflict_inlier_ratio() != 0) c.laser_conflict_inlier_ratio = o.laser_conflict_inlier_ratio();
  if (given(o.global_confirm_travel_m(), "grid2d", "global_confirm_travel_m")) c.global_confirm_travel_m = o.global_confirm_travel_m();
  if (o.global_after_lost_scans() < 0)
    throw OptionError("grid2d", "global_after_lost_scans", "must be >= 0 (0: never), got " + std::to_string(o.global_after_lost_scans()));
  c.global_after_lost_scans = o.global_after_lost_scans();
  if (given(o.global_confirm_inlier_ratio(), "grid2d", "global_confirm_inlier_ratio"))
    c.global_confirm_inlier_ratio = o.global_confirm_inlier_ratio();
  if (o.global_budget_s() < 0) c.global_budget_s = 0;  // no budget
  else if (o.global_budget_s() > 0) c.global_budget_s = o.global_budget_s();
  return c;
}

}  // namespace fploc::config
