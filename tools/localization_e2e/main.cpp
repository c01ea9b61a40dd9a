// localization_e2e: one simulated sequence through segmenter -> features -> matcher -> optimizer (and
// the odometry baseline), library level, no LCM. Prints JSON with the paper's columns; optionally writes
// TUM trajectories and an SVG plot. The `fploc bench paper` tool is the lead's; this is its engine.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iostream>

#include "fploc/core/text_out.h"
#include "fploc/eval/eval.h"
#include "fploc/floorplan/io.h"
#include "pipeline.h"

int main(int argc, char** argv) {
  CLI::App app{"localization_e2e: simulated sequence through the localization libraries"};
  fploc::e2e::Options o;
  std::string plan_file, out_prefix;
  std::vector<std::string> layers;
  std::string units;
  bool no_imu = false, no_clutter = false;
  app.add_option("--scenario", o.scenario);
  app.add_option("--seed", o.seed);
  app.add_option("--lookup", o.lookup);
  app.add_option("--max-frames", o.max_frames);
  app.add_option("--window", o.window);
  app.add_option("--alpha", o.alpha);
  app.add_option("--beta", o.beta);
  app.add_option("--kf-distance", o.keyframe_distance_m);
  app.add_option("--matcher-points", o.matcher_points);
  app.add_option("--optimizer-points", o.optimizer_points);
  app.add_option("--relook", o.relook_m, "optimizer re-look-up distance [m] (its angle scales along)");
  app.add_option("--drop", o.drop_fraction, "fraction of scans dropped");
  app.add_option("--noise", o.range_noise_m, "range noise sigma [m] (default: the simulator's)");
  app.add_option("--wall-clutter", o.wall_clutter, "fraction of the walls hidden behind 2 m cabinets");
  app.add_option("--frames-csv", o.frames_csv, "per-frame matcher diagnostics against the ground truth");
  app.add_option("--gt-offset", o.gt_offset_s, "ground truth time = scan start + this [s]");
  app.add_option("--init-error", [&](const std::vector<std::string>& v) {
    o.init_dx = std::stod(v.at(0));
    o.init_dy = std::stod(v.at(1));
    o.init_dyaw = std::stod(v.at(2)) * M_PI / 180;
    return true;
  }, "dx dy dyaw_deg")->expected(3);
  app.add_option("--init-search", o.init_search_m, "matcher's first-frame search radius around the initial pose [m]");
  app.add_option("--plan", plan_file);
  app.add_option("--layers", layers)->delimiter(',');
  app.add_option("--units", units);
  app.add_option("--out", out_prefix, "write PREFIX-{gt,sfr,wo,odo}.tum and PREFIX.svg");
  app.add_flag("--no-imu", no_imu);
  app.add_flag("--body-velocity", o.body_frame_velocity, "optimizer: body-frame velocity regularisation");
  app.add_flag("--gt-gravity", o.gt_gravity, "diagnostic: project the features with the true roll/pitch");
  app.add_flag("--no-clutter", no_clutter);
  bool json_flag = false;  // the output is JSON anyway; --json as every other tool takes it (it was refused)
  app.add_flag("--json", json_flag, "JSON on stdout (what it prints in any case)");
  CLI11_PARSE(app, argc, argv);
  o.imu = !no_imu;
  o.clutter = !no_clutter;
  if (std::filesystem::exists(FPLOC_SHARED_DIR)) o.shared_dir = FPLOC_SHARED_DIR;
  try {
    fploc::FloorPlan plan;
    if (!plan_file.empty()) plan = fploc::load_floor_plan(plan_file, layers, units);
    const auto r = fploc::e2e::run(plan, o);
    nlohmann::json j = {{"scenario", o.scenario}, {"seed", o.seed}, {"lookup", o.lookup}, {"frames", r.frames},
                        {"ok_frames", r.ok_frames}, {"lost_frames", r.lost_frames}, {"length_m", r.length_m},
                        {"avg_speed_mps", r.avg_speed}, {"max_speed_mps", r.max_speed}, {"ate_sfr_m", r.ate_sfr},
                        {"rpe_sfr_m", r.rpe_sfr}, {"ate_wo_m", r.ate_wo}, {"rpe_wo_m", r.rpe_wo},
                        {"ate_odometry_m", r.ate_odo}, {"rpe_odometry_m", r.rpe_odo},
                        {"ate_sfr_xy_m", r.ate_sfr_xy}, {"rpe_sfr_xy_m", r.rpe_sfr_xy}, {"ate_wo_xy_m", r.ate_wo_xy},
                        {"rpe_wo_xy_m", r.rpe_wo_xy}, {"ate_odometry_xy_m", r.ate_odo_xy}, {"rpe_odometry_xy_m", r.rpe_odo_xy},
                        {"features_per_scan", r.features_per_scan},
                        {"us_per_scan", {{"segmenter", r.us_segment}, {"features", r.us_features}, {"matcher", r.us_matcher},
                                         {"optimizer", r.us_optimizer}, {"odometry", r.us_odometry}}},
                        {"hz", 1e6 / std::max(1.0, r.us_segment + r.us_features + r.us_matcher + r.us_optimizer)}};
    std::cout << fploc::json_text(j, 2) << "\n";
    if (!out_prefix.empty()) {
      fploc::write_tum(out_prefix + "-gt.tum", r.gt);
      fploc::write_tum(out_prefix + "-sfr.tum", r.sfr);
      fploc::write_tum(out_prefix + "-wo.tum", r.wo);
      fploc::write_tum(out_prefix + "-odo.tum", r.odo);
      std::ofstream(out_prefix + ".svg") << fploc::eval::plot_svg(r.gt, r.wo, o.scenario + " (windowed)");
    }
  } catch (const std::exception& e) {
    std::cerr << "localization_e2e: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
