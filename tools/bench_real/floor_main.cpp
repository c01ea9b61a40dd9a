// fploc-real-floor LOG[.gz] --map MAP.yaml --first-scan S [--end-scan E] [--fit-loss L] [--start-offset M] :
// how well a localizer that matches the map exactly can agree with the reference. Every scan of [S, E) is refined
// against the map's distance field (modules/laser2d GridLocalizer, the same search + Ceres fit as fploc-grid2d)
// starting from its own reference pose (restarted at every scan: no tracking, no odometry, search +-0.3 m / +-6
// deg), and the fit's offset from the reference is printed per scan as JSON (`fploc bench real` reports its RMSE
// over the covered scans as the "floor": the map, built from the first part's scans at their reference poses, and
// the reference poses of the rest disagree by that much, as fploc's fit measures it). The fit's loss is part of
// that figure: with --fit-loss cauchy the same fits lie nearer the reference on every Radish log, also when started
// --start-offset 5 or 10 cm away (docs/notes/real2d.md, fifteenth pass), so it is a floor of the Huber objective,
// not of the map.
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "fploc/carmen/carmen.h"
#include "fit_loss_option.h"
#include "log_scans.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/laser2d/grid_localizer.h"

int main(int argc, char** argv) {
  CLI::App app{"fploc real-floor: per scan, the map fit's offset from the reference pose (fit started at the reference)"};
  std::string log_path, map_path;
  size_t first = 0, end = 0;
  app.add_option("log", log_path, "CARMEN log (.log or .log.gz)")->required();
  app.add_option("--map", map_path, "map_server occupancy map (.yaml)")->required();
  app.add_option("--first-scan", first, "first scan index")->required();
  app.add_option("--end-scan", end, "end scan index (exclusive; 0 = the log's end)");
  fploc::laser2d::GridLocalizerConfig c;
  fploc::bench_real::add_fit_loss_option(app, c.fit_loss);
  double offset_m = 0;
  app.add_option("--start-offset", offset_m,
                 "start each fit this far [m] from the reference, in a direction that turns by 137.5 deg per scan "
                 "(a check that the fit's optimum, not its start, sets the floor)");
  CLI11_PARSE(app, argc, argv);
  namespace cm = fploc::carmen;
  namespace l2 = fploc::laser2d;
  try {
    c.initial_sigma_xy_m = 0.1;
    c.initial_sigma_yaw_rad = 2.0 * M_PI / 180;
    // The floor is the map's own best single-scan fit from the reference pose: the search's best refined, as
    // before the odometry-consistent choice (which prefers the start pose and is a tracking rule, not a floor).
    c.consistent_candidates = 0;
    c.odometry_yaw_candidate = false;
    c.retry_window_factor = 1.0;
    const fploc::bench_real::LogScans scans = fploc::bench_real::load_log_scans(log_path, first, end, c.max_range_m);
    const cm::Log& log = scans.log;
    end = scans.end;
    const auto field = std::make_shared<fploc::DistanceField>(fploc::read_occupancy_map(map_path), c.field_max_m);
    l2::GridLocalizer loc(field, c);
    nlohmann::json rows = nlohmann::json::array();
    for (size_t k = first; k < end; ++k) {
      const auto& s = log.scans[k];
      const fploc::Pose2 ref{s.pose.x, s.pose.y, s.pose.theta};
      const double dir = double(k) * 137.5 * M_PI / 180;
      loc.set_initial_pose({ref.x + offset_m * std::cos(dir), ref.y + offset_m * std::sin(dir), ref.yaw});
      const double rmax = scans.max_range_m;
      const auto pts = l2::scan_points(s.ranges, -M_PI / 2, cm::beam_increment(s.ranges.size()), c.min_range_m, rmax);
      const l2::GridResult r = loc.update(pts, std::nullopt);
      rows.push_back({{"scan", k}, {"x", r.pose.x}, {"y", r.pose.y}, {"yaw", r.pose.yaw}, {"dxy_m", std::hypot(r.pose.x - ref.x, r.pose.y - ref.y)},
                      {"dyaw_deg", fploc::wrap_angle(r.pose.yaw - ref.yaw) * 180 / M_PI},
                      {"inlier_ratio", r.inlier_ratio}, {"ok", r.status == l2::GridStatus::kOk}});
    }
    std::cout << fploc::json_text(nlohmann::json{{"log", log_path}, {"map", map_path}, {"scans", rows}}) << "\n";
  } catch (const std::exception& ex) {
    std::cerr << "fploc real-floor: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
