#include "fploc/config/laser2d.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "fploc/config/check.h"

namespace fploc::config {

laser2d::GridLocalizerConfig config_of(const Grid2dOptions& o) {
  laser2d::GridLocalizerConfig c;
  constexpr double kRad = M_PI / 180;
  if (o.initial_sigma_xy_m() > 0) c.initial_sigma_xy_m = o.initial_sigma_xy_m();
  if (o.initial_sigma_yaw_deg() > 0) c.initial_sigma_yaw_rad = o.initial_sigma_yaw_deg() * kRad;
  if (o.min_range_m() > 0) c.min_range_m = o.min_range_m();
  if (o.max_range_m() > 0) c.max_range_m = o.max_range_m();
  if (o.min_inlier_ratio() > 0) c.min_inlier_ratio = o.min_inlier_ratio();
  if (o.field_max_m() > 0) c.field_max_m = o.field_max_m();
  if (o.min_inlier_ratio_near() > 0) c.min_inlier_ratio_near = o.min_inlier_ratio_near();
  if (o.gate_sigmas() > 0) c.gate_sigmas = o.gate_sigmas();
  if (o.sigma_xy_per_m() > 0) c.sigma_xy_per_m = o.sigma_xy_per_m();
  if (o.sigma_yaw_per_rad() > 0) c.sigma_yaw_per_rad = o.sigma_yaw_per_rad();
  if (o.prior_weight_sigmas() > 0) c.prior_weight_sigmas = o.prior_weight_sigmas();
  if (o.has_laser_odometry()) c.laser_odometry = o.laser_odometry();
  if (o.laser_map_scans() > 0) c.laser.map_scans = o.laser_map_scans();
  if (o.confirm_within_sigmas() != 0) c.confirm_within_sigmas = o.confirm_within_sigmas();
  if (o.far_confirm_travel_m() != 0) c.far_confirm_travel_m = o.far_confirm_travel_m();
  if (!o.fit_loss().empty()) {
    const auto loss = laser2d::fit_loss_from_name(o.fit_loss());
    if (!loss)
      throw OptionError("grid2d", "fit_loss", "unknown loss '" + o.fit_loss() +
                                                       "' (use \"huber\", \"cauchy\" or \"tukey\")");
    c.fit_loss = *loss;
  }
  if (o.huber_m() > 0) c.huber_m = o.huber_m();
  if (o.huber_first_above_sigma_m() > 0) c.huber_first_above_sigma_m = o.huber_first_above_sigma_m();
  if (o.laser_conflict_inlier_ratio() != 0) c.laser_conflict_inlier_ratio = o.laser_conflict_inlier_ratio();
  return c;
}

}  // namespace fploc::config
