#include "fploc/config/localization.h"

#include <algorithm>
#include <cmath>
#include <sstream>
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
matcher::AsBuiltModel as_built_of(const O& o, const char* block) {
  matcher::AsBuiltModel m;
  if (o.as_built_sigma_m() < 0) {
    std::ostringstream v;
    v << o.as_built_sigma_m();
    throw OptionError(block, "as_built_sigma_m", "must be >= 0 (0 = off), got " + v.str());
  }
  m.sigma_m = o.as_built_sigma_m();
  if (given(o.as_built_point_sigma_m(), block, "as_built_point_sigma_m")) m.point_sigma_m = o.as_built_point_sigma_m();
  if (o.as_built_loss_scale_m() != 0) m.loss_scale_m = std::max(0.0, o.as_built_loss_scale_m());
  m.keep_information = !o.as_built_free_information();
  if (given(o.as_built_max_spread_sigmas(), block, "as_built_max_spread_sigmas"))
    m.max_spread_sigmas = o.as_built_max_spread_sigmas();
  if (given(o.as_built_max_askew_m(), block, "as_built_max_askew_m"))
    m.max_askew_m = o.as_built_max_askew_m();
  return m;
}

}  // namespace
namespace {
constexpr double kRadPerDeg = M_PI / 180;
}  // namespace

matcher::MatcherConfig config_of(const MatcherOptions& o) {
  matcher::MatcherConfig c;
  if (given(o.max_correspondence_m(), "matcher", "max_correspondence_m")) c.max_correspondence_m = o.max_correspondence_m();
  if (given(o.min_correspondence_m(), "matcher", "min_correspondence_m")) c.min_correspondence_m = o.min_correspondence_m();
  if (given(o.loss_scale_m(), "matcher", "loss_scale_m")) c.loss_scale_m = o.loss_scale_m();
  if (!o.loss().empty()) c.loss = checked_loss(o.loss(), "matcher");
  if (given(o.max_iterations(), "matcher", "max_iterations")) c.max_iterations = o.max_iterations();
  if (given(o.max_rounds(), "matcher", "max_rounds")) c.max_rounds = o.max_rounds();
  if (given(o.inlier_m(), "matcher", "inlier_m")) c.inlier_m = o.inlier_m();
  if (given(o.min_inlier_ratio(), "matcher", "min_inlier_ratio")) c.min_inlier_ratio = o.min_inlier_ratio();
  if (given(o.min_inliers(), "matcher", "min_inliers")) c.min_inliers = o.min_inliers();
  if (given(o.lost_after(), "matcher", "lost_after")) c.lost_after = o.lost_after();
  if (given(o.max_jump_m(), "matcher", "max_jump_m")) c.max_jump_m = o.max_jump_m();
  if (given(o.max_jump_deg(), "matcher", "max_jump_deg")) c.max_jump_rad = o.max_jump_deg() * kRadPerDeg;
  c.group_rule = !o.disable_group_rule();
  c.motion_model = !o.disable_motion_model();
  if (given(o.stride(), "matcher", "stride")) c.stride = o.stride();
  if (o.max_points() != 0) c.max_points = o.max_points() < 0 ? 0 : o.max_points();
  if (given(o.element_quota(), "matcher", "element_quota")) c.element_quota = o.element_quota();
  if (given(o.askew_max_m(), "matcher", "askew_max_m")) c.askew_max_m = o.askew_max_m();
  c.deskew = !o.disable_deskew();
  if (o.prediction_sigma_m() != 0) c.prediction_sigma_m = std::max(0.0, o.prediction_sigma_m());
  if (o.prediction_sigma_deg() != 0) c.prediction_sigma_rad = std::max(0.0, o.prediction_sigma_deg()) * kRadPerDeg;
  if (o.odom_gate_sigmas() != 0) c.odom_gate_sigmas = std::max(0.0, o.odom_gate_sigmas());
  if (o.max_speed_mps() != 0) c.max_speed_mps = std::max(0.0, o.max_speed_mps());
  if (o.gap_s() != 0) c.gap_s = std::max(0.0, o.gap_s());
  if (given(o.gap_max_search_m(), "matcher", "gap_max_search_m")) c.gap_max_search_m = o.gap_max_search_m();
  c.as_built = as_built_of(o, "matcher");
  return c;
}

optimizer::OptimizerConfig config_of(const OptimizerOptions& o) {
  optimizer::OptimizerConfig c;
  if (given(o.window(), "optimizer", "window")) c.window = o.window();
  if (given(o.alpha(), "optimizer", "alpha")) c.alpha = o.alpha();
  if (given(o.beta(), "optimizer", "beta")) c.beta = o.beta();
  if (o.disable_regularisation()) c.alpha = c.beta = 0;
  if (given(o.keyframe_distance_m(), "optimizer", "keyframe_distance_m")) c.keyframe_distance_m = o.keyframe_distance_m();
  if (given(o.keyframe_angle_deg(), "optimizer", "keyframe_angle_deg")) c.keyframe_angle_rad = o.keyframe_angle_deg() * kRadPerDeg;
  if (given(o.gate_m(), "optimizer", "gate_m")) c.gate_m = o.gate_m();
  if (given(o.loss_scale_m(), "optimizer", "loss_scale_m")) c.loss_scale_m = o.loss_scale_m();
  if (!o.loss().empty()) c.loss = checked_loss(o.loss(), "optimizer");
  if (given(o.max_iterations(), "optimizer", "max_iterations")) c.max_iterations = o.max_iterations();
  if (given(o.rounds(), "optimizer", "rounds")) c.rounds = o.rounds();
  if (given(o.stride(), "optimizer", "stride")) c.stride = o.stride();
  if (o.max_points() != 0) c.max_points = o.max_points() < 0 ? 0 : o.max_points();
  if (given(o.element_quota(), "optimizer", "element_quota")) c.element_quota = o.element_quota();
  if (given(o.askew_max_m(), "optimizer", "askew_max_m")) c.askew_max_m = o.askew_max_m();
  if (given(o.max_keyframe_gap_s(), "optimizer", "max_keyframe_gap_s")) c.max_keyframe_gap_s = o.max_keyframe_gap_s();
  if (o.keyframe_interval_s() != 0) c.keyframe_interval_s = std::max(0.0, o.keyframe_interval_s());
  if (o.max_final_delay_s() != 0) c.max_final_delay_s = std::max(0.0, o.max_final_delay_s());
  c.anchor_final = o.anchor_final();
  c.body_frame_velocity = o.body_frame_velocity();
  if (given(o.relook_m(), "optimizer", "relook_m")) {
    c.relook_rad *= o.relook_m() / c.relook_m;  // the angle scales along
    c.relook_m = o.relook_m();
  }
  if (!o.linear_solver().empty()) c.linear_solver = o.linear_solver();
  c.budget_weight = !o.disable_budget_weight();
  c.group_rule = !o.disable_group_rule();
  c.as_built = as_built_of(o, "optimizer");
  return c;
}

odometry::OdometryConfig config_of(const OdometryOptions& o) {
  odometry::OdometryConfig c;
  if (given(o.max_correspondence_m(), "odometry", "max_correspondence_m")) c.max_correspondence_m = o.max_correspondence_m();
  if (given(o.keyframe_distance_m(), "odometry", "keyframe_distance_m")) c.keyframe_distance_m = o.keyframe_distance_m();
  if (given(o.keyframe_angle_deg(), "odometry", "keyframe_angle_deg")) c.keyframe_angle_rad = o.keyframe_angle_deg() * kRadPerDeg;
  if (given(o.map_keyframes(), "odometry", "map_keyframes")) c.map_keyframes = o.map_keyframes();
  if (given(o.max_iterations(), "odometry", "max_iterations")) c.max_iterations = o.max_iterations();
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
  if (given(o.initial_search_m(), "matcher", "initial_search_m")) c.initial_search_m = o.initial_search_m();
  return c;
}

localizer::Config localizer_config(const OptimizerOptions& o) {
  localizer::Config c;
  c.optimizer = config_of(o);
  return c;
}

}  // namespace fploc::config
