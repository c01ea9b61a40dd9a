// fploc-real-track LOG[.gz] --map MAP.yaml --first-scan S [--end-scan E] [--start ref|off|global] : fploc-grid2d's
// tracker (modules/laser2d GridLocalizer, the node's own point extraction and odometry pairing) run in-process
// over scans [S, E) of a CARMEN log, without LCM: per scan the estimate, the reference, the status, the fit's
// inlier share and the CPU time of the update, as JSON. The bench's numbers come from `fploc replay` of the
// lidar2d graph (fploc bench real); this is the same computation for looking at one log's errors scan by scan
// (tools/bench_real/plot_errors.py), for profiling, and for `fploc bench real --rows global` (global starts at
// many scans of a log: a replay per start would cost a whole graph run each).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <ctime>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "fploc/carmen/carmen.h"
#include "fit_loss_option.h"
#include "log_scans.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/laser2d/grid_localizer.h"

namespace {
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc real-track: grid2d's tracker over a CARMEN log's scans, in-process, per-scan JSON"};
  std::string log_path, map_path, start = "ref";
  size_t first = 0, end = 0;
  double laser_sigma_yaw_deg = -1;
  app.add_option("log", log_path, "CARMEN log (.log or .log.gz)")->required();
  app.add_option("--map", map_path, "map_server occupancy map (.yaml)")->required();
  app.add_option("--first-scan", first, "first scan index")->required();
  app.add_option("--end-scan", end, "end scan index (exclusive; 0 = the log's end)");
  app.add_option("--start", start, "ref: the reference pose of the first scan; off: 1 m / 10 deg off (as the bench); "
                                   "global: no pose, the whole map searched (GridLocalizer::start_global)")
      ->check(CLI::IsMember({"ref", "off", "global"}));
  std::vector<double> start_pose;
  app.add_option("--start-pose", start_pose, "X Y YAW: start here instead (e.g. the bench's start as read back from TUM)")
      ->expected(3);
  fploc::laser2d::GridLocalizerConfig c;
  app.add_option("--refine-candidates", c.refine_candidates, "distinct search candidates refined per scan");
  app.add_option("--candidate-ratio", c.candidate_ratio, "kept when >= this share of the best score");
  app.add_option("--reacquire-after", c.reacquire_after, "POOR scans after which jumps need confirmation");
  app.add_option("--follow-weak", c.follow_weak, "follow weak near fits while re-acquiring");
  app.add_option("--reacquire", c.reacquire, "re-acquisition with hypotheses");
  app.add_option("--follow-weak-when-lost", c.follow_weak_when_lost, "follow weak near fits also once LOST");
  app.add_option("--consistent-candidates", c.consistent_candidates, "odometry-consistent choice among this many candidates (<= 0: off)");
  app.add_option("--jump-inlier-margin", c.jump_inlier_margin, "inlier share a fit away from the prediction needs over the nearest");
  app.add_option("--odometry-yaw-candidate", c.odometry_yaw_candidate, "also refine the prediction with its yaw held");
  app.add_option("--retry-window-factor", c.retry_window_factor, "retry a failed tracking fit in a window this much wider (1: off)");
  app.add_option("--dead-reckoning-motion-only", c.dead_reckoning_motion_only, "POOR scans: uncertainty grows with the motion only");
  app.add_option("--reacquire-strong-ratio", c.reacquire_strong_ratio, "re-acquiring: a fit inside the window with this inlier share ends it");
  app.add_option("--confirm-inlier-ratio", c.confirm_inlier_ratio, "mean inlier share to take a hypothesis");
  app.add_option("--reacquire-xy", c.reacquire_xy_m, "re-acquisition window [m]");
  app.add_option("--calibrate-odometry", c.calibrate_odometry, "learn the wheels' yaw bias / turn scale / scale from good fits");
  app.add_option("--calibration-memory", c.calibration.memory_m, "calibration forgetting distance [m]");
  app.add_option("--lost-after", c.lost_after, "POOR scans before LOST");
  app.add_option("--lost-window-from-sigma", c.lost_window_from_sigma, "LOST searches +-3 sigma of the dead-reckoned pose, not the whole window");
  app.add_option("--prior-bias", c.calibration.prior_bias_m2, "calibration ridge on the yaw bias [m^2]");
  app.add_option("--prior-turn", c.calibration.prior_turn_rad2, "calibration ridge on the turn scale [rad^2]");
  app.add_option("--prior-scale", c.calibration.prior_scale_m2, "calibration ridge on the scale [m^2]");
  app.add_option("--reacquire-search-every-m", c.reacquire_search_every_m, "wide re-acquisition search after this much travel (0: every scan)");
  app.add_option("--confirm-within-sigmas", c.confirm_within_sigmas, "a hypothesis is taken within this many sigma of the dead-reckoned pose (<= 0: off)");
  app.add_option("--far-confirm-travel", c.far_confirm_travel_m, "a hypothesis beyond --confirm-within-sigmas is taken after this much travel with --reacquire-strong-ratio mean inliers (< 0: never)");
  app.add_option("--rival-margin", c.rival_margin, "re-acquiring: a near fit ends POOR/LOST only without a rival within this inlier share (< 0: off)");
  app.add_option("--weak-follow-step-only", c.weak_follow_step_only, "re-acquiring: follow a weak fit only within this step's own odometry sigma");
  app.add_option("--confirm-scans", c.confirm_scans, "scans a hypothesis must match in a row");
  app.add_option("--confirm-margin", c.confirm_margin, "mean inlier share a hypothesis needs over its runner-up");
  app.add_option("--point-sigma", c.point_sigma_m, "the map fit's per-return sigma [m] (its weight against the prediction)");
  app.add_option("--laser-conflict-inlier-ratio", c.laser_conflict_inlier_ratio, "tracking: a fit beyond the gate of a laser step needs this inlier share (0: off)");
  app.add_option("--laser-odometry", c.laser_odometry, "predict with the scan-to-recent-scans increment where it matches");
  app.add_option("--laser-map-scans", c.laser.map_scans, "laser odometry: scans in the local map");
  app.add_option("--laser-sigma-xy", c.laser_sigma_xy_m, "laser odometry: per-step sigma base [m]");
  app.add_option("--laser-sigma-xy-per-m", c.laser_sigma_xy_per_m, "laser odometry: sigma per metre of step");
  app.add_option("--laser-sigma-yaw-deg", laser_sigma_yaw_deg, "laser odometry: per-step yaw sigma base [deg]");
  app.add_option("--laser-min-inlier-ratio", c.laser.min_inlier_ratio, "laser odometry: share of the scan the local map must explain");
  app.add_option("--laser-wide-retry", c.laser_wide_retry, "laser odometry: re-acquiring, a strong fit in the wheels' window");
  app.add_option("--laser-track-retry", c.laser_track_retry, "laser odometry: a failed tracking fit, a strong fit in the wheels' window");
  app.add_option("--global-candidates", c.global_candidates, "global: distinct places proposed per whole-map search");
  app.add_option("--global-max-hypotheses", c.global_max_hypotheses, "global: places tracked at most");
  app.add_option("--global-sep", c.global_sep_xy_m, "global: the whole-map search's candidates are distinct beyond this [m]");
  double global_sep_deg = -1;
  app.add_option("--global-sep-deg", global_sep_deg, "global: ... or beyond this [deg]");
  app.add_option("--global-confirm-travel", c.global_confirm_travel_m, "global: travel [m] a place must have matched over");
  app.add_option("--global-confirm-inlier-ratio", c.global_confirm_inlier_ratio, "global: mean inlier share a place needs");
  app.add_option("--global-confirm-margin", c.global_confirm_margin, "global: mean inlier share over every other place still matching");
  app.add_option("--global-confirm-outlier-ratio", c.global_confirm_outlier_ratio, "global: every other place leaves this many times the leader's unexplained share (0: off)");
  app.add_option("--global-after-lost", c.global_after_lost_scans, "kidnapped robot: whole-map search after this many LOST scans (0: never)");
  // No budget by default here (grid2d's is 300 s): the bench measures how long a lock takes, and a log whose times do
  // not resolve its scans is spread evenly over its duration (csail: 24.7 s per scan, 300 s = 12 scans).
  c.global_budget_s = 0;
  app.add_option("--global-budget", c.global_budget_s, "global: give up after this many seconds of the log's time without a place taken (default 0: no budget)");
  fploc::bench_real::add_fit_loss_option(app, c.fit_loss);
  app.add_option("--huber", c.huber_m, "scale of the map fit's robust loss [m]");
  app.add_option("--huber-first-above", c.huber_first_above_sigma_m,
                 "redescending loss: Huber first when the prediction's sigma x/y exceeds this [m]");
  CLI11_PARSE(app, argc, argv);
  if (laser_sigma_yaw_deg >= 0) c.laser_sigma_yaw_rad = laser_sigma_yaw_deg * M_PI / 180;
  if (global_sep_deg >= 0) c.global_sep_yaw_rad = global_sep_deg * M_PI / 180;
  namespace cm = fploc::carmen;
  namespace l2 = fploc::laser2d;
  try {
    const fploc::bench_real::LogScans scans = fploc::bench_real::load_log_scans(log_path, first, end, c.max_range_m);
    const cm::Log& log = scans.log;
    end = scans.end;
    const fploc::OccupancyGrid grid = fploc::read_occupancy_map(map_path);
    const auto field = std::make_shared<fploc::DistanceField>(grid, c.field_max_m);
    l2::GridLocalizer loc(field, c);
    loc.set_free_space(grid);  // as fploc-grid2d
    if (start == "global" && start_pose.empty()) {
      loc.start_global();
    } else {
      fploc::Pose2 p0 = fploc::bench_real::start_pose(log, first, start == "global" ? "ref" : start);
      if (start_pose.size() == 3) p0 = {start_pose[0], start_pose[1], start_pose[2]};
      loc.set_initial_pose(p0);
    }
    const double rmax = scans.max_range_m;
    const std::vector<double> times = cm::scan_times(log);  // the global search's budget is in the log's time
    nlohmann::json rows = nlohmann::json::array();
    double total_ms = 0;
    for (size_t k = first; k < end; ++k) {
      const auto& s = log.scans[k];
      const double t0 = thread_cpu_ms();
      const auto pts = l2::scan_points(s.ranges, -M_PI / 2, cm::beam_increment(s.ranges.size()), c.min_range_m, rmax);
      std::optional<fploc::Pose2> odom;
      if (s.have_wheel_odom) odom = fploc::Pose2{s.wheel_odom.x, s.wheel_odom.y, s.wheel_odom.theta};
      const l2::GridResult r = loc.update(pts, odom, k < times.size() ? times[k] : std::numeric_limits<double>::quiet_NaN());
      const double ms = thread_cpu_ms() - t0;
      total_ms += ms;
      rows.push_back({{"scan", k}, {"x", r.pose.x}, {"y", r.pose.y}, {"yaw", r.pose.yaw}, {"ref_x", s.pose.x},
                      {"ref_y", s.pose.y}, {"ref_yaw", s.pose.theta},
                      {"err_m", std::hypot(r.pose.x - s.pose.x, r.pose.y - s.pose.y)},
                      {"err_yaw_deg", fploc::wrap_angle(r.pose.yaw - s.pose.theta) * 180 / M_PI},
                      {"status", int(r.status)}, {"inlier_ratio", r.inlier_ratio}, {"window_m", r.search_xy_m},
                      {"window_deg", r.search_yaw_rad * 180 / M_PI}, {"sigma_xy_m", std::sqrt(r.covariance(0, 0))},
                      {"cov", {r.covariance(0, 0), r.covariance(0, 1), r.covariance(0, 2), r.covariance(1, 1),
                               r.covariance(1, 2), r.covariance(2, 2)}},
                      {"rms_m", r.rms_m}, {"num_points", r.num_points},
                      {"hypotheses", r.hypotheses}, {"global", r.global}, {"ms", ms}, {"laser_step", r.laser_step},
                      {"laser_inlier_ratio", r.laser_inlier_ratio}, {"wide_search", r.wide_search},
                      {"odom_bias_deg_per_m", r.odom_bias_rad_per_m * 180 / M_PI},
                      {"odom_turn_scale_error", r.odom_turn_scale_error}, {"odom_scale", r.odom_scale}});
      if (odom) rows.back().update({{"odom_x", odom->x}, {"odom_y", odom->y}, {"odom_yaw", odom->yaw}});
      if (r.global || r.global_gave_up) rows.back().update({{"global_elapsed_s", r.global_elapsed_s}, {"global_gave_up", r.global_gave_up}});
      if (r.global) {
        nlohmann::json pl = nlohmann::json::array();
        for (const auto& q : r.places)
          pl.push_back({{"id", q.id}, {"x", q.pose.x}, {"y", q.pose.y}, {"yaw", q.pose.yaw}, {"hits", q.hits},
                        {"mean", q.mean_inlier_ratio}, {"min", q.min_inlier_ratio}, {"travel_m", q.travel_m},
                        {"err_m", std::hypot(q.pose.x - s.pose.x, q.pose.y - s.pose.y)},
                        {"err_yaw_deg", fploc::wrap_angle(q.pose.yaw - s.pose.theta) * 180 / M_PI}});
        rows.back()["places"] = pl;
      }
      if (r.laser_step)
        rows.back()["laser_increment"] = {r.laser_increment.x, r.laser_increment.y, r.laser_increment.yaw};
    }
    std::cout << fploc::json_text(nlohmann::json{{"log", log_path}, {"map", map_path}, {"start", start},
                                                 {"ms_per_scan", total_ms / double(end - first)}, {"scans", rows}})
              << "\n";
  } catch (const std::exception& ex) {
    std::cerr << "fploc real-track: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
