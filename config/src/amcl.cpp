#include "fploc/config/amcl.h"

#include <cmath>
#include <stdexcept>

#include "fploc/config/check.h"

namespace fploc::config {

amcl::Settings config_of(const AmclOptions& o) {
  amcl::Settings s;
  amcl::Config& c = s.filter;
  if (o.has_min_particles()) c.min_particles = o.min_particles();
  if (o.has_max_particles()) c.max_particles = o.max_particles();
  if (o.has_alpha1()) c.alpha1 = o.alpha1();
  if (o.has_alpha2()) c.alpha2 = o.alpha2();
  if (o.has_alpha3()) c.alpha3 = o.alpha3();
  if (o.has_alpha4()) c.alpha4 = o.alpha4();
  if (o.has_z_hit()) c.z_hit = o.z_hit();
  if (o.has_z_rand()) c.z_rand = o.z_rand();
  if (o.has_sigma_hit()) c.sigma_hit = o.sigma_hit();
  if (o.has_laser_likelihood_max_dist()) c.laser_likelihood_max_dist = o.laser_likelihood_max_dist();
  if (o.has_max_beams()) c.max_beams = o.max_beams();
  if (o.has_laser_max_range()) c.laser_max_range = o.laser_max_range();
  if (o.has_laser_min_range()) c.laser_min_range = o.laser_min_range();
  if (o.has_update_min_d()) c.update_min_d = o.update_min_d();
  if (o.has_update_min_a()) c.update_min_a = o.update_min_a();
  if (o.has_resample_interval()) c.resample_interval = o.resample_interval();
  if (o.has_pf_err()) c.pf_err = o.pf_err();
  if (o.has_pf_z()) c.pf_z = o.pf_z();
  if (o.has_recovery_alpha_slow()) c.recovery_alpha_slow = o.recovery_alpha_slow();
  if (o.has_recovery_alpha_fast()) c.recovery_alpha_fast = o.recovery_alpha_fast();
  if (o.resampler() == "low-variance") c.resampler = amcl::Resampler::kLowVariance;
  else if (!o.resampler().empty() && o.resampler() != "multinomial")
    throw OptionError("amcl", "resampler", "'" + o.resampler() + "' (use \"multinomial\" or \"low-variance\")");
  if (o.estimate() == "weighted-mean") c.estimate = amcl::EstimateMode::kWeightedMean;
  else if (!o.estimate().empty() && o.estimate() != "best-cluster")
    throw OptionError("amcl", "estimate", "'" + o.estimate() + "' (use \"best-cluster\" or \"weighted-mean\")");
  if (o.has_map_resolution()) c.map_resolution = o.map_resolution();
  if (o.has_free_clearance_m()) c.free_clearance = o.free_clearance_m();
  if (o.has_seed()) c.seed = o.seed();
  if (o.has_scan_bins()) s.scan.bins = o.scan_bins();
  if (s.scan.bins < 2) throw OptionError("amcl", "scan_bins", "must be >= 2");
  if (o.has_scan_range_min()) s.scan.range_min_m = o.scan_range_min();
  if (o.has_scan_range_max()) s.scan.range_max_m = o.scan_range_max();
  if (o.has_initial_std_xy_m()) s.initial.std_xy_m = o.initial_std_xy_m();
  if (o.has_initial_std_yaw_deg()) s.initial.std_yaw_deg = o.initial_std_yaw_deg();
  if (o.has_max_odom_step_m()) s.guard.max_step_m = o.max_odom_step_m();
  if (o.has_max_odom_step_deg()) s.guard.max_step_rad = o.max_odom_step_deg() * M_PI / 180.0;
  if (o.odometry().empty() || o.odometry() == "pose") {
    s.odometry = amcl::OdometrySource::kPose;
  } else if (o.odometry() == "simulated-wheel") {
    s.odometry = amcl::OdometrySource::kSimulatedWheel;
    const auto& w = o.wheel();
    if (w.has_scale_error()) s.wheel.scale_error = w.scale_error();
    if (w.has_yaw_drift_deg_per_m()) s.wheel.yaw_drift_deg_per_m = w.yaw_drift_deg_per_m();
    if (w.has_trans_noise_m_per_sqrt_m()) s.wheel.trans_noise_m_per_sqrt_m = w.trans_noise_m_per_sqrt_m();
    if (w.has_yaw_noise_deg_per_sqrt_m()) s.wheel.yaw_noise_deg_per_sqrt_m = w.yaw_noise_deg_per_sqrt_m();
    if (w.has_seed()) s.wheel.seed = w.seed();
  } else {
    throw OptionError("amcl", "odometry", "'" + o.odometry() + "' (use \"pose\" or \"simulated-wheel\")");
  }
  return s;
}

}  // namespace fploc::config
