// The defaults are written once, in the Config structs; the proto comments state them for the reader of
// a graph file. This test reads proto/options/*.proto and checks every default a comment states
// ("(0.3)", "(default 10)", "0 = default 0.4", "(0 = 5)") against config_of(Options{}) of that message,
// and that no stated default of a covered message is left unchecked.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "fploc/config/amcl.h"
#include "fploc/config/laser2d.h"
#include "fploc/config/recording.h"
#include "fploc/config/localization.h"
#include "fploc/config/perception.h"
#include "fploc/config/relocalization.h"

namespace {

using fploc::config::config_of;
constexpr double kDeg = 180 / M_PI;

// message -> field -> stated default (text as written), from the proto file.
std::map<std::string, std::map<std::string, std::string>> stated_defaults(const std::string& file) {
  std::ifstream in(std::string(FPLOC_SOURCE_DIR) + "/proto/options/" + file);
  EXPECT_TRUE(in) << file;
  std::map<std::string, std::map<std::string, std::string>> out;
  const std::regex msg_re(R"(^message (\w+) \{)");
  const std::regex field_re(R"(^\s+(?:repeated |optional )?\w+ (\w+) = \d+;\s*(?://(.*))?$)");
  const std::regex cont_re(R"(^\s+//(.*)$)");
  const std::regex def_res[] = {std::regex(R"(\(default (-?[0-9.]+)[;), ])"), std::regex(R"(0 = default (-?[0-9.]+))"),
                                std::regex(R"(\(0 = (-?[0-9.]+)[;), ])"), std::regex(R"(\((-?[0-9.]+)(?:[;),:]| [a-z=]))")};
  std::string msg, field, comment, line;
  auto flush = [&] {
    if (msg.empty() || field.empty()) return;
    std::smatch m;
    const std::string c = comment + " ";
    for (const auto& re : def_res)
      if (std::regex_search(c, m, re)) {
        out[msg][field] = m[1];
        break;
      }
    field.clear();
  };
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, msg_re)) {
      flush();
      msg = m[1];
    } else if (std::regex_match(line, m, field_re)) {
      flush();
      field = m[1];
      comment = m[2];
    } else if (std::regex_match(line, m, cont_re) && !field.empty()) {
      comment += " " + std::string(m[1]);
    } else {
      flush();
    }
  }
  flush();
  return out;
}

// Equal to the precision the comment is written with.
void expect_stated(const std::string& where, const std::string& text, double value) {
  const auto dot = text.find('.');
  const int decimals = dot == std::string::npos ? 0 : int(text.size() - dot - 1);
  EXPECT_LE(std::abs(std::stod(text) - value), 0.5 * std::pow(10.0, -decimals) + 1e-12)
      << where << ": the proto comment says " << text << ", the Config default is " << value;
}

using Table = std::map<std::string, double>;

void check(const std::string& file, const std::string& message, const Table& table,
           const std::set<std::string>& not_a_config_default = {}) {
  const auto stated = stated_defaults(file);
  ASSERT_TRUE(stated.count(message)) << message << " in " << file << " states no default";
  for (const auto& [field, text] : stated.at(message)) {
    if (not_a_config_default.count(field)) continue;
    const auto it = table.find(field);
    if (it == table.end()) {
      ADD_FAILURE() << file << " " << message << "." << field << " states a default (" << text
                    << "): add it to this test's table";
      continue;
    }
    expect_stated(file + " " + message + "." + field, text, it->second);
  }
  for (const auto& [field, value] : table)
    EXPECT_TRUE(stated.at(message).count(field)) << message << "." << field << ": its comment states no default";
}

TEST(ConfigDefaults, Matcher) {
  const fploc::matcher::MatcherConfig c = config_of(fploc::MatcherOptions{});
  check("localization.proto", "MatcherOptions",
        {{"max_correspondence_m", c.max_correspondence_m}, {"loss_scale_m", c.loss_scale_m},
         {"max_iterations", c.max_iterations}, {"min_inlier_ratio", c.min_inlier_ratio},
         {"min_correspondence_m", c.min_correspondence_m}, {"max_rounds", c.max_rounds}, {"inlier_m", c.inlier_m},
         {"min_inliers", c.min_inliers}, {"lost_after", c.lost_after}, {"max_jump_m", c.max_jump_m},
         {"max_jump_deg", c.max_jump_rad * kDeg}, {"stride", c.stride}, {"max_points", c.max_points},
         {"prediction_sigma_m", c.prediction_sigma_m}, {"prediction_sigma_deg", c.prediction_sigma_rad * kDeg},
         {"odom_gate_sigmas", c.odom_gate_sigmas}, {"as_built_sigma_m", c.as_built.sigma_m},
         {"as_built_point_sigma_m", c.as_built.point_sigma_m},
         {"as_built_loss_scale_m", c.as_built.loss_scale_m}, {"element_quota", c.element_quota},
         {"as_built_max_spread_sigmas", c.as_built.max_spread_sigmas},
         {"as_built_max_askew_m", c.as_built.max_askew_m}, {"askew_max_m", c.askew_max_m},
         {"max_speed_mps", c.max_speed_mps}, {"gap_s", c.gap_s}, {"gap_max_search_m", c.gap_max_search_m}});
}

TEST(ConfigDefaults, Optimizer) {
  const fploc::optimizer::OptimizerConfig c = config_of(fploc::OptimizerOptions{});
  check("localization.proto", "OptimizerOptions",
        {{"window", c.window}, {"alpha", c.alpha}, {"beta", c.beta}, {"keyframe_distance_m", c.keyframe_distance_m},
         {"keyframe_angle_deg", c.keyframe_angle_rad * kDeg}, {"gate_m", c.gate_m}, {"loss_scale_m", c.loss_scale_m},
         {"max_iterations", c.max_iterations}, {"rounds", c.rounds}, {"stride", c.stride},
         {"max_keyframe_gap_s", c.max_keyframe_gap_s}, {"keyframe_interval_s", c.keyframe_interval_s},
         {"max_final_delay_s", c.max_final_delay_s},
         {"max_points", c.max_points}, {"relook_m", c.relook_m},
         {"as_built_sigma_m", c.as_built.sigma_m}, {"as_built_point_sigma_m", c.as_built.point_sigma_m},
         {"as_built_loss_scale_m", c.as_built.loss_scale_m}, {"element_quota", c.element_quota},
         {"as_built_max_spread_sigmas", c.as_built.max_spread_sigmas},
         {"as_built_max_askew_m", c.as_built.max_askew_m}, {"askew_max_m", c.askew_max_m}});
}

TEST(ConfigDefaults, Odometry) {
  const fploc::odometry::OdometryConfig c = config_of(fploc::OdometryOptions{});
  check("localization.proto", "OdometryOptions",
        {{"max_correspondence_m", c.max_correspondence_m}, {"keyframe_distance_m", c.keyframe_distance_m},
         {"keyframe_angle_deg", c.keyframe_angle_rad * kDeg}, {"map_keyframes", c.map_keyframes},
         {"max_iterations", c.max_iterations}});
}

TEST(ConfigDefaults, Perception) {
  const fploc::seg::SegmenterConfig s = config_of(fploc::SegmenterOptions{});
  // ransac_max_iterations: fploc-segmenter-ransac's own argument, not a SegmenterConfig field.
  check("perception.proto", "SegmenterOptions",
        {{"seed_rings", s.seed_rings}, {"max_tilt_deg", s.max_tilt_deg}, {"wall_margin_m", s.wall_margin_m},
         {"min_range_m", s.min_range_m}, {"inlier_threshold_m", s.inlier_threshold_m},
         {"min_plane_inliers", s.min_plane_inliers}, {"irls_iterations", s.irls_iterations},
         {"seed_triplets", s.seed_triplets}},
        {"ransac_max_iterations"});
  const fploc::feat::FeatureConfig f = config_of(fploc::FeatureOptions{});
  check("perception.proto", "FeatureOptions",
        {{"sectors", f.sectors}, {"max_corners_per_sector", f.max_corners_per_sector},
         {"max_surfaces_per_sector", f.max_surfaces_per_sector}, {"corner_threshold", f.corner_threshold},
         {"surface_threshold", f.surface_threshold}, {"max_range_m", f.max_range_m}, {"min_range_m", f.min_range_m},
         {"half_window", f.half_window}, {"min_group_points", f.min_group_points}, {"line_max_rms_m", f.line_max_rms_m},
         {"column_front_m", f.column_front_m}, {"high_band_m", f.high_band_m}, {"high_min_points", f.high_min_points},
         {"high_same_surface_m", f.high_same_surface_m},
         {"high_keep_unseen", f.high_keep_unseen}});
}

TEST(ConfigDefaults, Relocalizer) {
  const fploc::reloc::RelocalizerConfig c = config_of(fploc::RelocalizerOptions{});
  // region_radius_m, global_after_s, min_interval_s: fploc-relocalizer's scheduling, not RelocalizerConfig.
  check("relocalization.proto", "RelocalizerOptions",
        {{"grid_m", c.grid_m}, {"yaw_step_deg", c.yaw_step_deg}, {"min_inlier_ratio", c.min_inlier_ratio},
         {"min_evidence", c.min_evidence}},
        {"region_radius_m", "global_after_s", "min_interval_s", "max_speed_mps", "speed_margin_m"});
  const fploc::reloc::Schedule w = fploc::config::schedule_of(fploc::RelocalizerOptions{});
  check("relocalization.proto", "RelocalizerOptions",
        {{"region_radius_m", w.region_radius_m}, {"global_after_s", w.global_after_s}, {"min_interval_s", w.min_interval_s},
         {"max_speed_mps", w.max_speed_mps}, {"speed_margin_m", w.speed_margin_m}},
        {"grid_m", "yaw_step_deg", "min_inlier_ratio", "min_evidence"});
}

TEST(ConfigDefaults, Amcl) {
  const fploc::amcl::Settings s = config_of(fploc::AmclOptions{});
  const fploc::amcl::Config& c = s.filter;
  check("amcl.proto", "AmclOptions",
        {{"min_particles", c.min_particles}, {"max_particles", c.max_particles}, {"alpha1", c.alpha1},
         {"alpha2", c.alpha2}, {"alpha3", c.alpha3}, {"alpha4", c.alpha4}, {"z_hit", c.z_hit}, {"z_rand", c.z_rand},
         {"sigma_hit", c.sigma_hit}, {"laser_likelihood_max_dist", c.laser_likelihood_max_dist},
         {"max_beams", c.max_beams}, {"laser_max_range", c.laser_max_range}, {"laser_min_range", c.laser_min_range},
         {"update_min_d", c.update_min_d}, {"update_min_a", c.update_min_a}, {"resample_interval", c.resample_interval},
         {"pf_err", c.pf_err}, {"pf_z", c.pf_z}, {"recovery_alpha_slow", c.recovery_alpha_slow},
         {"recovery_alpha_fast", c.recovery_alpha_fast}, {"map_resolution", c.map_resolution},
         {"free_clearance_m", c.free_clearance}, {"seed", double(c.seed)},
         {"scan_bins", s.scan.bins}, {"scan_range_min", s.scan.range_min_m}, {"scan_range_max", s.scan.range_max_m},
         {"initial_std_xy_m", s.initial.std_xy_m}, {"initial_std_yaw_deg", s.initial.std_yaw_deg},
         {"max_odom_step_m", s.guard.max_step_m}, {"max_odom_step_deg", s.guard.max_step_rad * kDeg}});
  check("amcl.proto", "WheelOdometryOptions",
        {{"scale_error", s.wheel.scale_error}, {"yaw_drift_deg_per_m", s.wheel.yaw_drift_deg_per_m},
         {"trans_noise_m_per_sqrt_m", s.wheel.trans_noise_m_per_sqrt_m},
         {"yaw_noise_deg_per_sqrt_m", s.wheel.yaw_noise_deg_per_sqrt_m}, {"seed", double(s.wheel.seed)}});
}

TEST(ConfigDefaults, Grid2d) {
  const fploc::laser2d::GridLocalizerConfig c = config_of(fploc::Grid2dOptions{});
  check("laser2d.proto", "Grid2dOptions",
        {{"initial_sigma_xy_m", c.initial_sigma_xy_m}, {"initial_sigma_yaw_deg", c.initial_sigma_yaw_rad * kDeg},
         {"min_range_m", c.min_range_m}, {"max_range_m", c.max_range_m}, {"min_inlier_ratio", c.min_inlier_ratio},
         {"field_max_m", c.field_max_m}, {"min_inlier_ratio_near", c.min_inlier_ratio_near},
         {"gate_sigmas", c.gate_sigmas}, {"sigma_xy_per_m", c.sigma_xy_per_m},
         {"sigma_yaw_per_rad", c.sigma_yaw_per_rad}, {"prior_weight_sigmas", c.prior_weight_sigmas},
         {"laser_map_scans", double(c.laser.map_scans)}, {"confirm_within_sigmas", c.confirm_within_sigmas},
         {"far_confirm_travel_m", c.far_confirm_travel_m}, {"huber_m", c.huber_m},
         {"huber_first_above_sigma_m", c.huber_first_above_sigma_m},
         {"laser_conflict_inlier_ratio", c.laser_conflict_inlier_ratio},
         {"global_confirm_travel_m", c.global_confirm_travel_m},
         {"global_confirm_inlier_ratio", c.global_confirm_inlier_ratio}});
  EXPECT_EQ(c.fit_loss, fploc::laser2d::FitLoss::kHuber);
}

// laser_conflict_inlier_ratio: zero is the default, a negative value turns the rule off.
TEST(ConfigMapping, Grid2dLaserConflictOff) {
  fploc::Grid2dOptions o;
  o.set_laser_conflict_inlier_ratio(-1);
  EXPECT_LE(config_of(o).laser_conflict_inlier_ratio, 0);
  o.set_laser_conflict_inlier_ratio(0.8);
  EXPECT_EQ(config_of(o).laser_conflict_inlier_ratio, 0.8);
}

// The grid localizer's fit loss by name; an unknown name is one error naming the option.
TEST(ConfigMapping, Grid2dFitLoss) {
  fploc::Grid2dOptions o;
  o.set_fit_loss("cauchy");
  EXPECT_EQ(config_of(o).fit_loss, fploc::laser2d::FitLoss::kCauchy);
  o.set_fit_loss("tukey");
  EXPECT_EQ(config_of(o).fit_loss, fploc::laser2d::FitLoss::kTukey);
  o.set_fit_loss("Cauchy");
  try {
    (void)config_of(o);
    ADD_FAILURE() << "no error for fit_loss 'Cauchy'";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("grid2d.fit_loss: unknown loss 'Cauchy'"), std::string::npos) << e.what();
  }
}

TEST(ConfigDefaults, CloudToScan) {
  const fploc::rec::CloudOptions c = config_of(fploc::CloudToScanOptions{});
  check("recording.proto", "CloudToScanOptions",
        {{"rings", double(c.rings)}, {"columns", double(c.columns)}, {"gap_deg", c.gap_deg}});
}

}  // namespace

// Not a default, but the same mapping: an unknown robust loss is one error naming the option.
TEST(ConfigMapping, UnknownLossNamesTheOption) {
  fploc::MatcherOptions m;
  m.set_loss("cauchyy");
  try {
    (void)fploc::config::config_of(m);
    ADD_FAILURE() << "no error for loss 'cauchyy'";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("matcher.loss: unknown loss 'cauchyy'"), std::string::npos) << e.what();
  }
  fploc::OptimizerOptions o;
  o.set_loss("geman-mcclure");
  EXPECT_EQ(fploc::config::config_of(o).loss, "geman-mcclure");
  o.set_loss("L2");
  EXPECT_THROW((void)fploc::config::config_of(o), std::runtime_error);
}

// The matcher's odometry window: a negative option turns it off (max_jump_* only), zero keeps the default.
TEST(ConfigMapping, MatcherOdometryWindowOff) {
  fploc::MatcherOptions m;
  EXPECT_EQ(fploc::config::config_of(m).odom_gate_sigmas, fploc::matcher::MatcherConfig{}.odom_gate_sigmas);
  m.set_odom_gate_sigmas(-1);
  EXPECT_EQ(fploc::config::config_of(m).odom_gate_sigmas, 0.0);
  m.set_odom_gate_sigmas(4);
  EXPECT_EQ(fploc::config::config_of(m).odom_gate_sigmas, 4.0);
}
