// fploc-real-plan-track LOG[.gz] --map MAP.yaml --first-scan S [--end-scan E] [--start ref|off] : the lidar2d
// graph's plan path (fploc-laser2d's features -> the Localizer: matcher + window optimizer, with the wheel
// odometry's increments as the prediction) run in-process over scans [S, E) of a CARMEN log against the
// vectorised occupancy map, without LCM: per scan the window's estimate, the reference, the published status and
// the single-frame fit, as JSON. `fploc bench real` scores the same path through `fploc replay` of the graph
// (its `fploc_plan` rows); this one is for looking at a log scan by scan and for trying options.
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fploc/carmen/carmen.h"
#include "fploc/config/localization.h"
#include "fploc/config/plan_source.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/distance_field.h"
#include "fploc/laser2d/grid_localizer.h"
#include "fploc/laser2d/laser_odometry.h"
#include "fploc/laser2d/laser2d.h"
#include "fploc/localizer/localizer.h"
#include "log_scans.h"

int main(int argc, char** argv) {
  CLI::App app{"fploc real-plan-track: the lidar2d graph's plan path over a CARMEN log's scans, in-process"};
  std::string log_path, map_path, start = "ref";
  size_t first = 0, end = 0;
  fploc::MatcherOptions mo;
  mo.set_lookup("annf-exact");
  mo.set_max_correspondence_m(0.5);  // as graphs/lidar2d.pbtxt
  double initial_search = 0;
  double gate = 0;
  app.add_option("log", log_path, "CARMEN log (.log or .log.gz)")->required();
  app.add_option("--map", map_path, "map_server occupancy map (.yaml) or any plan")->required();
  app.add_option("--first-scan", first, "first scan index")->required();
  app.add_option("--end-scan", end, "end scan index (exclusive; 0 = the log's end)");
  app.add_option("--start", start, "ref: the reference pose of the first scan; off: 1 m / 10 deg off (as the bench)")
      ->check(CLI::IsMember({"ref", "off"}));
  app.add_option("--gate", gate, "matcher.max_correspondence_m (default: the lidar2d graph's 0.5)");
  app.add_option("--initial-search", initial_search, "matcher.initial_search_m: the start's uncertainty [m]");
  double plan_sigma = 0;
  double map_sigma = -1;
  app.add_option("--map-sigma", map_sigma, "the published covariance's map term [m] (default: the map's, an occupancy map's cell / sqrt(12); 0: none)");
  app.add_option("--plan-sigma", plan_sigma, "the published covariance's floor on each plan element's offset sigma [m]");
  bool no_group_rule = false, at_ref = false;
  app.add_flag("--at-reference", at_ref, "also register each frame alone from its reference pose (diagnostics)");
  app.add_flag("--no-group-rule", no_group_rule, "PCA line groups match independently (both steps)");
  bool laser_odom = false;
  app.add_flag("--laser-odometry", laser_odom,
               "the odometry is the scans' own increments (laser2d::LaserOdometry: each scan matched to the last scans, "
               "the wheels predicting; the wheels' step where a match fails), as grid2d uses; rows get odom_inc");
  // The matcher's odometry model (MatcherConfig::odom_sigma_*; default: the wheel model), e.g. for --laser-odometry.
  double osm = -1, ospm = -1, osr = -1, ospr = -1, osrpm = -1;
  app.add_option("--odom-sigma", osm, "odometry 1-sigma per step: base [m]");
  app.add_option("--odom-sigma-per-m", ospm, "... plus this share of the step");
  app.add_option("--odom-sigma-deg", osr, "odometry yaw 1-sigma per step: base [deg]");
  app.add_option("--odom-sigma-per-rad", ospr, "... plus this share of the turn");
  app.add_option("--odom-sigma-deg-per-m", osrpm, "... plus this many deg per metre of the step");
  CLI11_PARSE(app, argc, argv);
  if (gate > 0) mo.set_max_correspondence_m(gate);
  if (initial_search > 0) mo.set_initial_search_m(initial_search);
  fploc::OptimizerOptions oo;
  mo.set_disable_group_rule(no_group_rule);
  oo.set_disable_group_rule(no_group_rule);
  namespace cm = fploc::carmen;
  try {
    const fploc::bench_real::LogScans scans = fploc::bench_real::load_log_scans(log_path, first, end, 1000.0);
    const cm::Log& log = scans.log;
    end = scans.end;
    const std::vector<double> times = cm::scan_times(log);
    fploc::PlanSource ps;
    ps.set_file(map_path);
    const fploc::matcher::LocalizationMap map =
        fploc::config::load_map(ps, mo.lookup(), [](const std::string& p) { return p; }, "--map");
    fploc::localizer::Config cfg = fploc::config::localizer_config(mo);
    cfg.optimizer = fploc::config::localizer_config(oo).optimizer;
    cfg.uncertainty.frame.plan_sigma_m = plan_sigma;
    fploc::localizer::use_map(cfg, map);
    if (map_sigma >= 0) cfg.map_sigma_m = map_sigma;
    if (osm >= 0) cfg.matcher.odom_sigma_m = osm;
    if (ospm >= 0) cfg.matcher.odom_sigma_per_m = ospm;
    if (osr >= 0) cfg.matcher.odom_sigma_rad = osr * M_PI / 180;
    if (ospr >= 0) cfg.matcher.odom_sigma_per_rad = ospr;
    if (osrpm >= 0) cfg.matcher.odom_sigma_rad_per_m = osrpm * M_PI / 180;
    fploc::laser2d::LaserOdometry lodo;
    std::optional<fploc::Pose2> last_wheel;
    fploc::Pose2 lo_pose{};
    int lo_kept = 0, lo_n = 0;
    std::optional<fploc::Pose2> lo_row_inc;  // this scan's odometry increment (laser or wheels), for the row
    fploc::localizer::Localizer loc(*map.lookup, cfg);
    // --at-reference on an occupancy map: the same share on its raster (the grid localizer's view of it).
    const bool raster = at_ref && map_path.size() > 5 && map_path.substr(map_path.size() - 5) == ".yaml";
    const fploc::DistanceField df =
        raster ? fploc::DistanceField(fploc::read_occupancy_map(map_path), 1.0) : fploc::DistanceField();
    // The share of a frame's points at pose p that land in the map's known free space (beyond the inlier distance
    // from any occupied cell: what the map says is empty) and in unknown space / off the map.
    auto free_unknown = [&](const fploc::FeatureFrame& f, const fploc::Pose2& p) {
      int fr = 0, un = 0;
      const double c = std::cos(p.yaw), sn = std::sin(p.yaw);
      for (const auto& q : f.points) {
        const Eigen::Vector2d w(p.x + c * q.p.x() - sn * q.p.y(), p.y + sn * q.p.x() + c * q.p.y());
        un += !map.free_space->known(w);
        fr += map.free_space->free(w, loc.config().matcher.inlier_m);
      }
      const double n = std::max<size_t>(1, f.points.size());
      return std::pair<double, double>(fr / n, un / n);
    };
    fploc::laser2d::Laser2dFeatures l2{fploc::laser2d::Laser2dConfig{}};
    fploc::Pose2 p0 = fploc::bench_real::start_pose(log, first, start);
    loc.set_pose(p0);
    nlohmann::json rows = nlohmann::json::array();
    std::vector<fploc::localizer::Pose> finals;
    for (size_t k = first; k < end; ++k) {
      const auto& s = log.scans[k];
      fploc::laser2d::PlanarScan ps2;
      ps2.utime = int64_t(std::llround((times[k] - times[0]) * 1e6)) + 1000000;
      ps2.seq = int64_t(k);
      ps2.angle_min = float(-M_PI / 2);
      ps2.angle_increment = float(cm::beam_increment(s.ranges.size()));
      ps2.range_max = float(std::min(scans.max_range_m, 1000.0));
      ps2.ranges = s.ranges;
      if (laser_odom && s.have_wheel_odom) {
        const fploc::Pose2 w{s.wheel_odom.x, s.wheel_odom.y, s.wheel_odom.theta};
        const fploc::Pose2 inc = last_wheel ? fploc::between(*last_wheel, w) : fploc::Pose2{};
        const double step = std::hypot(inc.x, inc.y), turn = std::abs(inc.yaw);
        const auto pts = fploc::laser2d::scan_points(s.ranges, -M_PI / 2, cm::beam_increment(s.ranges.size()), 0.05,
                                                     std::min(scans.max_range_m, 1000.0) - 0.01);
        const auto st = lodo.update(pts, inc, 0.05 + 0.3 * step, 2 * M_PI / 180 + 0.3 * turn + 3 * M_PI / 180 * step);
        ++lo_n;
        if (st) ++lo_kept;
        if (last_wheel) lo_pose = fploc::compose(lo_pose, st ? st->increment : inc);
        lo_row_inc = last_wheel ? std::optional<fploc::Pose2>(st ? st->increment : inc) : std::nullopt;
        last_wheel = w;
        loc.add_odometry(ps2.utime, lo_pose);
      } else if (s.have_wheel_odom) loc.add_odometry(ps2.utime, {s.wheel_odom.x, s.wheel_odom.y, s.wheel_odom.theta});
      const fploc::FeatureFrame& f = l2.process(ps2);
      const auto step = loc.process(f, &finals);
      const auto& m = step.sfr.match;
      const fploc::Pose2 est = step.latest ? step.latest->pose : m.pose;
      nlohmann::json row = {{"scan", k}, {"x", est.x}, {"y", est.y}, {"yaw", est.yaw}, {"ref_x", s.pose.x},
                            {"ref_y", s.pose.y}, {"ref_yaw", s.pose.theta},
                            {"err_m", std::hypot(est.x - s.pose.x, est.y - s.pose.y)},
                            {"err_yaw_deg", fploc::wrap_angle(est.yaw - s.pose.theta) * 180 / M_PI},
                            {"sfr_err_m", std::hypot(m.pose.x - s.pose.x, m.pose.y - s.pose.y)},
                            {"sfr_status", fploc::matcher::to_string(m.status)}, {"sfr_text", m.text},
                            {"points", m.fit.num_points}, {"inlier_ratio", m.fit.inlier_ratio}, {"rms_m", m.fit.rms_m},
                            {"status", int(loc.uncertainty().status)}, {"why", loc.uncertainty().text}};
      if (lo_row_inc) row["odom_inc"] = {lo_row_inc->x, lo_row_inc->y, lo_row_inc->yaw};
      if (step.latest) {
        const Eigen::Matrix3d& c = step.latest->covariance;
        row["cov"] = {c(0, 0), c(0, 1), c(0, 2), c(1, 1), c(1, 2), c(2, 2)};
      }
      if (at_ref) {
        // The frame registered alone from its reference pose: how well the plan explains it there.
        const auto rf = fploc::matcher::register_frame(*map.lookup, f, {s.pose.x, s.pose.y, s.pose.theta}, loc.config().matcher);
        row["ref_fit_inlier_ratio"] = rf.fit.inlier_ratio;
        row["ref_fit_err_m"] = std::hypot(rf.pose.x - s.pose.x, rf.pose.y - s.pose.y);
        row["ref_fit_status"] = fploc::matcher::to_string(rf.status);
        // The points at the reference pose itself: share within the inlier distance of their nearest element.
        int near = 0, n = 0, near_df = 0;
        const double c = std::cos(s.pose.theta), sn = std::sin(s.pose.theta);
        for (const auto& q : f.points) {
          const Eigen::Vector2d w(s.pose.x + c * q.p.x() - sn * q.p.y(), s.pose.y + sn * q.p.x() + c * q.p.y());
          int ids[8];
          const int k = map.lookup->candidates(w, ids, 8);
          double best = 1e9;
          for (int i = 0; i < k; ++i) best = std::min(best, fploc::distance(map.lookup->targets()[size_t(ids[i])], w));
          near += best <= loc.config().matcher.inlier_m;
          if (raster) near_df += df.nearest(w) <= loc.config().matcher.inlier_m;
          ++n;
        }
        row["ref_inliers_at_ref"] = n ? double(near) / n : 0.0;
        if (map.free_space) {
          const auto [fe, ue] = free_unknown(f, est);
          const auto [fr, ur] = free_unknown(f, {s.pose.x, s.pose.y, s.pose.theta});
          row["free_at_est"] = fe;
          row["unknown_at_est"] = ue;
          row["free_at_ref"] = fr;
          row["unknown_at_ref"] = ur;
        }
        if (raster) row["ref_inliers_at_ref_grid"] = n ? double(near_df) / n : 0.0;
      }
      rows.push_back(row);
    }
    if (laser_odom) std::cerr << "laser odometry: " << lo_kept << " of " << lo_n << " steps matched\n";
    std::cout << fploc::json_text(nlohmann::json{{"log", log_path}, {"map", map_path}, {"start", start}, {"scans", rows}}) << "\n";
  } catch (const std::exception& ex) {
    std::cerr << "fploc real-plan-track: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
