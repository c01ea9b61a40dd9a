#include "fploc/config/localization.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fploc/config/check.h"

namespace fploc::config {

namespace {

// The robust losses plan_terms knows; anything else is one clear error naming the option.
const std::string& checked_loss(const std::string& loss, const char* block) {
  if (loss == "cauchy" || loss == "geman-mcclure" || loss == "huber" || loss == "none") return loss;
  throw OptionError(block, "loss", "unknown loss '" + loss + "' (use \"cauchy\", \"geman-mcclure\", \"huber\" or \"none\")");
}

// The as-built model's options (the same fields in MatcherOptions and OptimizerOptions).
template <class O>
matcher::AsBuiltModel as_built_of(const O& o) {
  matcher::AsBuiltModel m;
  m.sigma_m = std::max(0.0, o.as_built_sigma_m());
  if (o.as_built_point_sigma_m() > 0) m.point_sigma_m = o.as_built_point_sigma_m();
  if (o.as_built_loss_scale_m() != 0) m.loss_scale_m = std::max(0.0, o.as_built_loss_scale_m());
  m.keep_information = !o.as_built_free_information();
  return m;
}

}  // namespace
namespace {
constexpr double kRadPerDeg = M_PI / 180;
}  // namespace

matcher::MatcherConfig config_of(const MatcherOptions& o) {
  matcher::MatcherConfig c;
  if (o.max_correspondence_m() > 0) c.max_correspondence_m = o.max_correspondence_m();
  if (o.min_correspondence_m() > 0) c.min_correspondence_m = o.min_correspondence_m();
  if (o.loss_scale_m() > 0) c.loss_scale_m = o.loss_scale_m();
  if (!o.loss().empty()) c.loss = checked_loss(o.loss(), "matcher");
  if (o.max_iterations() > 0) c.max_iterations = o.max_iterations();
  if (o.max_rounds() > 0) c.max_rounds = o.max_rounds();
  if (o.inlier_m() > 0) c.inlier_m = o.inlier_m();
  if (o.min_inlier_ratio() > 0) c.min_inlier_ratio = o.min_inlier_ratio();
  if (o.min_inliers() > 0) c.min_inliers = o.min_inliers();
  if (o.lost_after() > 0) c.lost_after = o.lost_after();
  if (o.max_jump_m() > 0) c.max_jump_m = o.max_jump_m();
  if (o.max_jump_deg() > 0) c.max_jump_rad = o.max_jump_deg() * kRadPerDeg;
  c.group_rule = !o.disable_group_rule();
  c.motion_model = !o.disable_motion_model();
  if (o.stride() > 0) c.stride = o.stride();
  if (o.max_points() != 0) c.max_points = o.max_points() < 0 ? 0 : o.max_points();
  c.deskew = !o.disable_deskew();
  if (o.prediction_sigma_m() != 0) c.prediction_sigma_m = std::max(0.0, o.prediction_sigma_m());
  if (o.prediction_sigma_deg() != 0) c.prediction_sigma_rad = std::max(0.0, o.prediction_sigma_deg()) * kRadPerDeg;
  if (o.odom_gate_sigmas() != 0) c.odom_gate_sigmas = std::max(0.0, o.odom_gate_sigmas());
  c.as_built = as_built_of(o);
  return c;
}

optimizer::OptimizerConfig config_of(const OptimizerOptions& o) {
  optimizer::OptimizerConfig c;
  if (o.window() > 0) c.window = o.window();
  if (o.alpha() > 0) c.alpha = o.alpha();
  if (o.beta() > 0) c.beta = o.beta();
  if (o.disable_regularisation()) c.alpha = c.beta = 0;
  if (o.keyframe_distance_m() > 0) c.keyframe_distance_m = o.keyframe_distance_m();
  if (o.keyframe_angle_deg() > 0) c.keyframe_angle_rad = o.keyframe_angle_deg() * kRadPerDeg;
  if (o.gate_m() > 0) c.gate_m = o.gate_m();
  if (o.loss_scale_m() > 0) c.loss_scale_m = o.loss_scale_m();
  if (!o.loss().empty()) c.loss = checked_loss(o.loss(), "optimizer");
  if (o.max_iterations() > 0) c.max_iterations = o.max_iterations();
  if (o.rounds() > 0) c.rounds = o.rounds();
  if (o.stride() > 0) c.stride = o.stride();
  if (o.max_points() != 0) c.max_points = o.max_points() < 0 ? 0 : o.max_points();
  if (o.max_keyframe_gap_s() > 0) c.max_keyframe_gap_s = o.max_keyframe_gap_s();
  if (o.keyframe_interval_s() != 0) c.keyframe_interval_s = std::max(0.0, o.keyframe_interval_s());
  if (o.max_final_delay_s() != 0) c.max_final_delay_s = std::max(0.0, o.max_final_delay_s());
  c.anchor_final = o.anchor_final();
  c.body_frame_velocity = o.body_frame_velocity();
  if (o.relook_m() > 0) {
    c.relook_rad *= o.relook_m() / c.relook_m;  // the angle scales along
    c.relook_m = o.relook_m();
  }
  if (!o.linear_solver().empty()) c.linear_solver = o.linear_solver();
  c.budget_weight = !o.disable_budget_weight();
  c.group_rule = !o.disable_group_rule();
  c.as_built = as_built_of(o);
  return c;
}

odometry::OdometryConfig config_of(const OdometryOptions& o) {
  odometry::OdometryConfig c;
  if (o.max_correspondence_m() > 0) c.max_correspondence_m = o.max_correspondence_m();
  if (o.keyframe_distance_m() > 0) c.keyframe_distance_m = o.keyframe_distance_m();
  if (o.keyframe_angle_deg() > 0) c.keyframe_angle_rad = o.keyframe_angle_deg() * kRadPerDeg;
  if (o.map_keyframes() > 0) c.map_keyframes = o.map_keyframes();
  if (o.max_iterations() > 0) c.max_iterations = o.max_iterations();
  if (o.frame_to_frame()) {
    c.map_keyframes = 1;
    c.keyframe_distance_m = 0;
    c.keyframe_angle_rad = 0;
  }
  return c;
}

localizer::Config localizer_config(const MatcherOptions& o) {
  localizer::Config c;
  c.matcher = config_of(o);
  c.use_imu = !o.ignore_imu();
  if (o.initial_search_m() > 0) c.initial_search_m = o.initial_search_m();
  return c;
}

localizer::Config localizer_config(const OptimizerOptions& o) {
  localizer::Config c;
  c.optimizer = config_of(o);
  return c;
}

}  // namespace fploc::config
