// fploc import-carmen LOG[.gz] --out LOG.lcm [--tum REF.tum] [--begin F] [--end F]
//                    [--map DIR --map-begin F --map-end F --resolution M] [--json]
// A CARMEN log (the Radish 2D laser logs, modules/carmen) -> an LCM log that `fploc replay` and
// lcm-logplayer accept: LASER_SCAN (laser_scan_t, one per FLASER: 180 degrees from -90, ranges at the
// scanner's maximum are no return) and WHEEL_ODOM (pose_t: the last wheel-odometry ODOM record before the
// scan, stamped with the scan's time, as fploc-amcl's "pose" odometry pairs them), and the FLASER poses (the
// corrected laser poses: the reference) as TUM. --begin/--end select scans by index fraction (e.g. the second
// half); --map writes a map_server occupancy map (DIR/map.{pgm,yaml}) built from the scans and reference poses
// of --map-begin..--map-end (e.g. the first half): the non-circular protocol of `fploc bench real`.
// --odom-tum writes the WHEEL_ODOM poses as TUM too (the odometry's own frame; e.g. the third trajectory of
// `fploc eval --hat`, which estimates the reference's own noise).
// --refine-map-poses N: before the map is rasterised, its scans' poses are refined by N passes of each scan aligned
// to the others' scans with a prior on its reference pose (modules/laser2d/map_refine.h): the reference's per-pose
// noise no longer blurs the map's walls. 0 (default): the reference poses as they are.
#include <fploc/laser_scan_t.hpp>
#include <fploc/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "fploc/core/text_out.h"
#include "fploc/runtime/cli_messages.h"
#include "fploc/runtime/cli_numbers.h"
#include "fploc/carmen/carmen.h"
#include "fploc/carmen/coverage.h"
#include "fploc/laser2d/grid_localizer.h"
#include "fploc/laser2d/map_refine.h"
#include "fploc/runtime/log_writer.h"

namespace {

using fploc::rt::write_event;

void quat_of_yaw(double yaw, double q[4]) {
  q[0] = 0;
  q[1] = 0;
  q[2] = std::sin(yaw / 2);
  q[3] = std::cos(yaw / 2);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc import-carmen: CARMEN log (Radish) -> LCM log (laser_scan_t + odometry) + reference TUM"};
  fploc::rt::install_cli_messages(app, "fploc import-carmen");
  std::string in, out, tum, odom_tum, map_dir;
  double begin = 0, end = 1, map_begin = 0, map_end = 0.5, resolution = 0.05;
  bool json = false;
  fploc::carmen::GridConfig gcfg;
  std::string odom_from = "odom";
  bool auto_split = false;
  fploc::carmen::SplitRule rule;
  fploc::carmen::CoverageConfig ccfg;
  app.option_defaults()->always_capture_default();  // --help shows every option's default
  app.add_option("log", in, "CARMEN log (.log or .log.gz)")->required();
  app.add_option("--out", out, "LCM log to write");
  app.add_option("--tum", tum, "reference (FLASER poses) as TUM");
  app.add_option("--odom-tum", odom_tum, "the odometry of the WHEEL_ODOM events (--odom-from) as TUM, at the scans' times");
  app.add_option("--begin", begin, "first scan, as a fraction of the log's scans")->check(CLI::Range(0.0, 1.0));
  app.add_option("--end", end, "end (exclusive), fraction")->check(CLI::Range(0.0, 1.0));
  app.add_option("--map", map_dir, "write DIR/map.pgm + DIR/map.yaml from --map-begin..--map-end");
  app.add_option("--map-begin", map_begin, "first mapping scan, fraction")->check(CLI::Range(0.0, 1.0));
  app.add_option("--map-end", map_end, "end of the mapping scans (exclusive), fraction")->check(CLI::Range(0.0, 1.0));
  app.add_option("--resolution", resolution, "map cell size [m]")->check(CLI::PositiveNumber);
  app.add_flag("--json", json, "summary as JSON on stdout");
  app.add_option("--occupied-ratio", gcfg.occupied_ratio, "map: occupied when hits >= this share of hits + pass-throughs")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--min-hits", gcfg.min_hits, "map: occupied needs at least this many hits")->check(CLI::PositiveNumber);
  app.add_option("--hit-clearance", gcfg.hit_clearance_m, "map: a beam marks no cell within this [m] of its hit free")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--odom-from", odom_from,
                 "odom: the ODOM records (wheel odometry); flaser: the FLASER odom_* columns (in the corrected "
                 "Radish logs a copy of the reference: a diagnostic, circular)")
      ->check(CLI::IsMember({"odom", "flaser"}));
  app.add_flag("--auto-split", auto_split,
               "choose the split by the coverage rule (modules/carmen/coverage.h): map from scans [0, S), the LCM log "
               "and TUM from [S, --end); overrides --begin, --map-begin, --map-end");
  app.add_option("--split-min", rule.min_fraction, "auto split: smallest candidate fraction")->check(CLI::Range(0.0, 1.0));
  app.add_option("--split-max", rule.max_fraction, "auto split: largest candidate fraction")->check(CLI::Range(0.0, 1.0));
  app.add_option("--split-step", rule.step, "auto split: candidate step")->check(CLI::Range(0.001, 1.0));
  app.add_option("--split-covered-share", rule.covered_share,
                 "auto split: share of the remaining scans the prefix must cover")->check(CLI::Range(0.0, 1.0));
  app.add_option("--coverage-radius", ccfg.radius_m, "a return within this [m] of a mapped cell is covered")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--coverage-ratio", ccfg.covered_ratio, "a scan is covered when this share of its returns is")
      ->check(CLI::Range(0.0, 1.0));
  fploc::laser2d::MapRefineConfig rcfg;
  rcfg.passes = 0;
  app.add_option("--refine-map-poses", rcfg.passes,
                 "map: refine the mapping scans' poses by this many passes of scan-to-others alignment with a prior on "
                 "the reference pose before rasterising (modules/laser2d/map_refine.h; 0: the reference poses)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--refine-prior-sigma", rcfg.prior_sigma_xy_m, "map refinement: the reference pose's prior sigma [m]")
      ->check(CLI::PositiveNumber);
  app.add_option("--refine-highpass", rcfg.highpass_scans,
                 "map refinement: remove the corrections' moving mean over +-N scans after each pass (0: off)")
      ->check(CLI::NonNegativeNumber);
  std::string refine_method = "lines";
  app.add_option("--refine-method", refine_method,
                 "map refinement: lines (each point to the others' mean line) or field (the grid localizer's fit on "
                 "the distance field of the others' hits)")
      ->check(CLI::IsMember({"lines", "field"}));
  std::string map_poses_out;
  app.add_option("--map-poses-out", map_poses_out,
                 "map: write the mapping scans' poses (\"scan x y theta ref_x ref_y ref_theta\": as rasterised, and the "
                 "reference) to this file");
  CLI11_PARSE(app, argc, argv);
  if (!fploc::rt::check_finite_options(app, "fploc import-carmen", std::cerr)) return 1;  // nan, inf: one error naming the option
  namespace cm = fploc::carmen;
  // A log cut short or damaged part way: what came before the damage is written as usual, then the error (exit 1).
  std::string damage;
  try {
    std::string text = cm::read_maybe_gz(in, &damage);
    if (!damage.empty()) text.erase(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);  // a cut last line
    std::string bad_record;
    const cm::Log log = [&] {
      try {
        return cm::parse_log(text, in, &bad_record);
      } catch (const std::runtime_error&) {
        if (!damage.empty()) throw std::runtime_error(damage);  // nothing whole before it: the damage is the error
        throw;
      }
    }();
    if (!bad_record.empty()) damage = bad_record;  // a bad record lies before a cut (the text ends at the cut)
    std::string note;
    const std::vector<double> t = cm::scan_times(log, &note);
    const float no_return = cm::no_return_range(log);
    const size_t n = log.scans.size();
    auto idx = [&](double f) { return std::min(n, size_t(std::llround(f * double(n)))); };
    size_t b = idx(begin), e = idx(end);
    ccfg.resolution = resolution;
    ccfg.no_return = no_return;
    nlohmann::json split_j;
    if (auto_split) {
      const auto first_cover = cm::prefix_coverage(log.scans, ccfg);
      const cm::Split sp = cm::choose_split(first_cover, rule);
      b = sp.split;
      map_begin = 0;
      map_end = double(sp.split) / double(n);
      split_j = {{"rule", {{"min_fraction", rule.min_fraction}, {"max_fraction", rule.max_fraction}, {"step", rule.step},
                           {"covered_share", rule.covered_share}, {"radius_m", ccfg.radius_m},
                           {"covered_ratio", ccfg.covered_ratio}}},
                 {"split", sp.split}, {"fraction", sp.fraction}, {"covered_share", sp.covered_share}, {"met", sp.met}};
    }
    if (e <= b) {
      // Say where the range starts and ends: with --auto-split the start is the split, not --begin.
      std::ostringstream m;
      m << std::setprecision(3);
      if (auto_split)
        m << "--end " << end << " selects no scans: the automatic split (--auto-split) is at " << double(b) / double(n)
          << " (scan " << b << " of " << n << "), and the scans to write run from the split to --end (scan " << e
          << "); give an --end above " << double(b) / double(n) << ", or --begin/--map-end instead of --auto-split";
      else
        m << "--begin " << begin << " / --end " << end << " select no scans (scans " << b << ".." << e << " of " << n << ")";
      throw std::runtime_error(m.str());
    }
    nlohmann::json j = {{"log", in}, {"scans_total", n}, {"odom_records", log.odom.size()},
                        {"odom_reanchors", log.odom_reanchors}, {"first_scan", b},
                        {"end_scan", e}, {"no_return_m", std::isfinite(no_return) ? double(no_return) : -1.0},
                        {"time_note", note}, {"beams", log.scans[0].ranges.size()}};
    for (const auto& [k, v] : log.skipped) j["skipped"][k] = v;
    if (auto_split) j["split"] = split_j;
    // Times: microseconds, starting at the log's first scan (whatever the log's epoch).
    const double t0 = t.front();
    auto utime_of = [&](size_t k) { return int64_t(std::llround((t[k] - t0) * 1e6)) + 1000000; };
    if (!out.empty()) {
      lcm::LogFile lf(out, "w");
      if (!lf.good()) throw std::runtime_error(out + ": cannot write");
      std::vector<uint8_t> buf;
      size_t odom = 0;
      for (size_t k = b; k < e; ++k) {
        const auto& s = log.scans[k];
        const int64_t ut = utime_of(k);
        const bool flaser = odom_from == "flaser";
        const auto& op = flaser ? s.odom : s.wheel_odom;
        if (flaser || s.have_wheel_odom) {
          fploc::pose_t p{};
          p.utime = ut;
          p.seq = int64_t(k);
          p.status = 0;
          p.floor_index = -1;  // wheel odometry frame: no floor
          p.position[0] = op.x;
          p.position[1] = op.y;
          quat_of_yaw(op.theta, p.orientation);
          write_event(lf, ut, "WHEEL_ODOM", p, buf);
          ++odom;
        }
        fploc::laser_scan_t m;
        m.utime = ut;
        m.frame = "flaser";
        m.angle_min = float(-M_PI / 2);
        m.angle_increment = float(cm::beam_increment(s.ranges.size()));
        m.time_increment = 0;  // not in the log
        m.range_min = 0.0f;
        m.range_max = std::isfinite(no_return) ? no_return : 1000.f;
        m.num_ranges = int32_t(s.ranges.size());
        m.ranges = s.ranges;
        m.num_intensities = 0;
        write_event(lf, ut, "LASER_SCAN", m, buf);
      }
      j["out"] = out;
      j["odom_events"] = odom;
    }
    // Poses of scans [b, e) as TUM, at the scans' times (skip: scans without such a pose).
    auto write_tum = [&](const std::string& path, const std::string& what, auto pose_of, auto has) {
      std::ofstream f(path);
      if (!f) throw std::runtime_error(path + ": cannot write");
      f << "# fploc import-carmen " << in << ": " << what << ", scans " << b << ".." << e << "\n";
      f << std::fixed << std::setprecision(6);
      for (size_t k = b; k < e; ++k) {
        if (!has(log.scans[k])) continue;
        const auto& p = pose_of(log.scans[k]);
        f << double(utime_of(k)) * 1e-6 << " " << p.x << " " << p.y << " 0 0 0 " << std::sin(p.theta / 2) << " "
          << std::cos(p.theta / 2) << "\n";
      }
      if (!f) throw std::runtime_error(path + ": write failed");
    };
    if (!tum.empty()) {
      write_tum(tum, "FLASER (corrected) laser poses", [](const auto& s) -> const auto& { return s.pose; },
                [](const auto&) { return true; });
      j["tum"] = tum;
    }
    if (!odom_tum.empty()) {
      const bool flaser = odom_from == "flaser";
      write_tum(odom_tum, flaser ? "FLASER odom columns" : "wheel odometry (the last ODOM record before each scan)",
                [&](const auto& s) -> const auto& { return flaser ? s.odom : s.wheel_odom; },
                [&](const auto& s) { return flaser || s.have_wheel_odom; });
      j["odom_tum"] = odom_tum;
    }
    if (!map_dir.empty()) {
      const size_t mb = auto_split ? 0 : idx(map_begin), me = auto_split ? b : idx(map_end);
      if (me <= mb) throw std::runtime_error("--map-begin/--map-end select no scans");
      std::vector<const cm::LaserRecord*> sel;
      for (size_t k = mb; k < me; ++k) sel.push_back(&log.scans[k]);
      // Refined poses: copies of the mapping scans with their poses replaced (the scored part keeps the reference).
      std::vector<cm::LaserRecord> refined;
      nlohmann::json refine_j;
      if (rcfg.passes > 0) {
        namespace l2 = fploc::laser2d;
        const double rmax = std::isfinite(no_return) ? std::min<double>(40.0, no_return) : 40.0;
        std::vector<std::vector<Eigen::Vector2d>> pts;
        std::vector<fploc::Pose2> poses;
        for (const auto* s : sel) {
          pts.push_back(l2::scan_points(s->ranges, -M_PI / 2, cm::beam_increment(s->ranges.size()), 0.1, rmax));
          poses.push_back({s->pose.x, s->pose.y, s->pose.theta});
        }
        l2::MapRefineStats rs;
        rcfg.method = refine_method == "field" ? l2::MapRefineMethod::kField : l2::MapRefineMethod::kLines;
        const auto out_poses = l2::refine_map_poses(pts, poses, rcfg, &rs);
        refined.reserve(sel.size());
        for (size_t k = 0; k < sel.size(); ++k) {
          refined.push_back(*sel[k]);
          refined.back().pose = {out_poses[k].x, out_poses[k].y, out_poses[k].yaw};
        }
        for (size_t k = 0; k < sel.size(); ++k) sel[k] = &refined[k];
        refine_j = {{"passes", rcfg.passes}, {"method", refine_method}, {"highpass_scans", rcfg.highpass_scans}, {"prior_sigma_xy_m", rcfg.prior_sigma_xy_m}, {"per_pass", nlohmann::json::array()}};
        for (const auto& p : rs.passes)
          refine_j["per_pass"].push_back({{"refined", p.refined}, {"kept", p.kept}, {"rms_shift_m", p.rms_shift_m},
                                          {"rms_from_reference_m", p.rms_from_start_m},
                                          {"rms_from_reference_yaw_rad", p.rms_from_start_yaw_rad},
                                          {"rms_residual_m", p.rms_residual_m}});
      }
      if (!map_poses_out.empty()) {
        std::ofstream f(map_poses_out);
        f << "# scan x y theta ref_x ref_y ref_theta\n" << std::setprecision(9);
        for (size_t k = 0; k < sel.size(); ++k) {
          const auto& r = log.scans[mb + k].pose;
          f << mb + k << " " << sel[k]->pose.x << " " << sel[k]->pose.y << " " << sel[k]->pose.theta << " " << r.x << " "
            << r.y << " " << r.theta << "\n";
        }
        if (!f) throw std::runtime_error(map_poses_out + ": write failed");
      }
      cm::GridConfig gc = gcfg;
      gc.resolution = resolution;
      gc.no_return = no_return;
      const cm::Grid g = cm::build_grid(sel, gc);
      cm::write_map_server(g, map_dir, "map");
      size_t occ = 0;
      for (auto c : g.cells) occ += c == 100;
      j["map"] = {{"dir", map_dir}, {"first_scan", mb}, {"end_scan", me}, {"width", g.width}, {"height", g.height},
                  {"resolution_m", resolution}, {"occupied_cells", occ}, {"min_hits", gc.min_hits},
                  {"occupied_ratio", gc.occupied_ratio}, {"hit_clearance_m", gc.hit_clearance_m}};
      if (rcfg.passes > 0) j["map"]["refine"] = refine_j;
      // Per scan of [b, e): the share of its returns within coverage_radius of an occupied cell of this map
      // at the reference pose (the bench scores the scans with >= coverage_ratio separately).
      j["coverage"] = cm::grid_coverage(g, log.scans, b, e, ccfg);
      j["coverage_ratio"] = ccfg.covered_ratio;
    }
    std::cerr << "fploc import-carmen: " << in << ": " << n << " scans (" << log.scans[0].ranges.size() << " beams), "
              << log.odom.size() << " odometry records"
              << (log.odom_reanchors ? " (+" + std::to_string(log.odom_reanchors) + " re-anchorings at scans: increments measured from them)" : "")
              << "; wrote scans " << b << ".." << e
              << (note.empty() ? "" : "; " + note) << "\n";
    if (!damage.empty()) j["damage"] = damage;  // the log ends there: what was read before it is all there is
    if (json) std::cout << fploc::json_text(j, 1) << "\n";  // file names: any bytes
    if (!damage.empty()) {
      std::cerr << "fploc import-carmen: " << damage << " (the log ends there: " << n
                << " scans read before it, scans " << b << ".." << e << " of them written)\n";
      return 1;
    }
  } catch (const std::exception& ex) {
    std::cerr << "fploc import-carmen: " << ex.what() << "\n";
    if (!damage.empty() && damage != ex.what()) std::cerr << "fploc import-carmen: (the log was damaged: " << damage << ")\n";
    return 1;
  }
  return 0;
}
