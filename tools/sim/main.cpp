// fploc sim --plan FILE --scenario NAME [--seed N] --out LOG.lcm --gt GT.tum
// Simulates an OS-1-64 (1024x10) and its IMU along a scenario trajectory and writes an LCM log directly:
// OS1_SCAN (scan_t, published at the end of each sweep), OS1_IMU (imu_t), FPLOC_GROUND_TRUTH
// (ground_truth_t, the sensor pose at each scan's first column time), plus the ground truth as TUM.
#include <CLI/CLI.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/scan_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <cstdio>

#include "fploc/core/text_out.h"
#include "fploc/runtime/cli_messages.h"
#include "fploc/runtime/cli_numbers.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"
#include "fploc/adapters/ground_truth_t.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/sim/demo_building.h"
#include "fploc/sim/simulator.h"
#include "fploc/runtime/log_writer.h"

namespace {

std::string shared_dir() {
  if (const char* e = std::getenv("FPLOC_SHARED_DIR"); e && *e) return e;
  return FPLOC_SHARED_DIR;
}

using fploc::rt::write_event;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc sim: simulate an OS-1-64 + IMU sequence into an LCM log and a TUM ground truth"};
  fploc::rt::install_cli_messages(app, "fploc sim");
  std::string plan_file, scenario, out, gt, units, metadata, beams, demo_dir, floor, world_file, perturb, truth, gt_floors,
      demo_building_dir, ceilings_building;
  std::vector<std::string> layers, gaps;
  uint64_t seed = 0;
  bool no_clutter = false, no_patches = false, json = false, no_thresholds = false, gap_imu = false;
  double noise = 0.02, dropout = 0.01, imu_rate = 100, duration = 0, ceiling = 0, wall_clutter = 0, drop_scans = 0;
  app.add_option("--plan", plan_file, "floor plan (.dxf/.csv/.json/.fpmap) or building (.pbtxt/.ifc); default: the scenario's demo plan");
  app.add_option("--layers", layers, "layer globs")->delimiter(',');
  app.add_option("--units", units, "m|cm|mm override");
  app.add_option("--floor", floor, "building (.pbtxt) or IFC plan: the floor simulated (default: the first; journeys start where they are drawn)");
  app.add_option("--gt-floors", gt_floors, "buildings: the ground-truth floor per scan, CSV t,floor_index,floor,state (default: GT without .tum + .floors.csv)");
  app.add_flag("--no-thresholds", no_thresholds, "buildings: no door thresholds");
  app.add_option("--write-demo-building", demo_building_dir, "write the demo building's plans (ground.json, first.json) into DIR and exit");
  app.add_option("--scenario", scenario, "room-small-loop|room-large-loop|room-no-loop|corridor-loop|auto-loop|building-areas|building-atrium|building-clutter|building-mixed + -slow|-medium|-fast; journeys through the demo building (--plan data/buildings/demo-building.pbtxt): building-twofloor|building-ramp|building-thresholds + -slow|-medium|-fast");
  app.add_option("--seed", seed, "random seed (noise, wobble, clutter)");
  app.add_option("--out", out, "LCM log to write");
  app.add_option("--gt", gt, "ground truth TUM file (one pose per scan, at the scan's first column time)");
  app.add_option("--metadata", metadata, "Ouster metadata JSON for the beam angles (default: --beams)");
  app.add_option("--beams", beams, "beam pattern: os1-64 (default), os1-32, os1-128 (real metadata from ../shared when "
                 "present, else nominal), vlp16 (16 beams, +-15 deg)");
  app.add_option("--noise", noise, "range noise sigma [m]");
  app.add_option("--dropout", dropout, "fraction of returns dropped");
  app.add_option("--imu-rate", imu_rate, "IMU rate [Hz]");
  app.add_option("--ceiling", ceiling, "ceiling height [m] (0 = scenario default)");
  app.add_option("--duration", duration, "stop after this many seconds (0 = whole scenario)");
  app.add_flag("--no-clutter", no_clutter, "no furniture or people");
  app.add_option("--wall-clutter", wall_clutter, "fraction of the wall length hidden behind 2 m cabinets (robustness tests)");
  app.add_option("--drop-scans", drop_scans, "fraction of scans left out of the log (deterministic for a seed; robustness tests)");
  app.add_option("--gap", gaps, "START:SECONDS: no scans from START for SECONDS (seconds from the sequence's start; "
                 "repeatable; ground truth and IMU stay): a sensor or network dropout");
  app.add_flag("--gap-imu", gap_imu, "--gap drops the IMU samples too (the OS-1's IMU comes over the same link)");
  app.add_flag("--no-ceiling-patches", no_patches, "flat ceiling everywhere");
  app.add_flag("--json", json, "print a JSON summary on stdout");
  app.add_option("--world", world_file, "the world the sensor sees, when it differs from the plan: a plan file or a world JSON (see modules/sim perturb.h)");
  app.add_option("--perturb", perturb, "seeded world perturbation of the plan: a family (" +
                 [] { std::string s; for (auto& n : fploc::sim::perturb_family_names()) s += (s.empty() ? "" : ", ") + n; return s; }() +
                 ") or key=value,... with the keys " + fploc::sim::perturb_keys_help());
  app.add_option("--truth", truth, "where to write the world-vs-plan truth JSON (default: LOG without .lcm + .world.json)");
  app.add_option("--ceilings-building", ceilings_building,
                 "building-* scenarios: write the simulated ceilings as a one-floor building file (.pbtxt) for the segmenter");
  app.add_option("--write-demo-plans", demo_dir, "write the demo plans (room.json, corridor.json) into DIR and exit");
  CLI11_PARSE(app, argc, argv);
  if (!fploc::rt::check_finite_options(app, "fploc sim", std::cerr)) return 1;  // nan, inf: one error naming the option

  try {
    if (!demo_dir.empty()) {
      std::filesystem::create_directories(demo_dir);
      fploc::save_floor_plan(fploc::sim::demo_room_plan(), demo_dir + "/room.json");
      fploc::save_floor_plan(fploc::sim::demo_corridor_plan(), demo_dir + "/corridor.json");
      std::cerr << "wrote " << demo_dir << "/room.json and corridor.json\n";
      return 0;
    }
    if (!demo_building_dir.empty()) {
      std::filesystem::create_directories(demo_building_dir);
      for (const auto& f : fploc::sim::demo_building_floors())
        fploc::save_floor_plan(fploc::sim::demo_building_plan(f), demo_building_dir + "/" + f + ".json");
      std::cerr << "wrote " << demo_building_dir << "/ground.json and first.json\n";
      return 0;
    }
    if (scenario.empty() || out.empty() || gt.empty()) {
      std::cerr << "fploc sim: --scenario, --out and --gt are required\n" << app.help();
      return 2;
    }
    fploc::FloorPlan plan;
    const bool is_building = !plan_file.empty() && fploc::is_building_file(plan_file);
    if (!plan_file.empty() && !is_building) plan = fploc::load_floor_plan(plan_file, layers, units, floor);
    fploc::sim::SimulatorOptions o;
    o.scenario = scenario;
    o.seed = seed;
    o.clutter = !no_clutter;
    if (!(wall_clutter >= 0 && wall_clutter <= 1)) throw std::runtime_error("--wall-clutter: expected a fraction 0..1");
    if (!(drop_scans >= 0 && drop_scans < 1)) throw std::runtime_error("--drop-scans: expected a fraction 0..1 (less than 1)");
    std::vector<std::pair<double, double>> gap_spans;  // [start, end) from the sequence's start
    for (const auto& g : gaps) {
      const auto c = g.find(':');
      char* e1 = nullptr;
      char* e2 = nullptr;
      const double a = c == std::string::npos ? NAN : std::strtod(g.c_str(), &e1);
      const double d = c == std::string::npos ? NAN : std::strtod(g.c_str() + c + 1, &e2);
      if (c == std::string::npos || c == 0 || e1 != g.c_str() + c || *e2 != 0 || !(a >= 0) || !(d > 0) || !std::isfinite(a + d))
        throw std::runtime_error("--gap " + g + ": expected START:SECONDS (both finite, START >= 0, SECONDS > 0)");
      gap_spans.emplace_back(a, a + d);
    }
    if (gap_imu && gap_spans.empty()) throw std::runtime_error("--gap-imu: needs --gap");
    o.wall_clutter = wall_clutter;
    o.ceiling_patches = !no_patches;
    o.range_noise_m = noise;
    o.dropout = dropout;
    o.metadata = metadata;
    o.beams = beams;
    o.shared_dir = shared_dir();
    o.imu_rate_hz = imu_rate;
    o.ceiling_height_m = ceiling;
    if (!world_file.empty() && !perturb.empty()) throw std::runtime_error("--world and --perturb exclude each other");
    if (!perturb.empty()) o.perturb = fploc::sim::parse_perturb(perturb);
    o.world_file = world_file;
    o.world_layers = layers;
    o.world_units = units;
    o.thresholds = !no_thresholds;
    if (!world_file.empty() && plan_file.empty() && scenario.rfind("auto-loop", 0) == 0)
      throw std::runtime_error("--world needs --plan for auto-loop scenarios (the path is planned on the plan)");
    const auto t_start = std::chrono::steady_clock::now();
    std::unique_ptr<fploc::sim::Simulator> simp;
    if (is_building) {
      fploc::PlanLoadOptions po;
      po.layer_globs = layers;
      po.units_override = units;
      simp = std::make_unique<fploc::sim::Simulator>(fploc::load_building(plan_file), floor, o, po);
    } else {
      simp = std::make_unique<fploc::sim::Simulator>(plan, o);
    }
    fploc::sim::Simulator& sim = *simp;
    std::cerr << "fploc sim: " << scenario << " seed " << seed << ", beams: " << sim.beam_source() << "\n" << sim.info();
    if (!ceilings_building.empty()) {
      if (sim.ceiling_map().areas.empty() && sim.ceiling_map().objects.empty())
        throw std::runtime_error("--ceilings-building: scenario " + scenario + " has no ceiling map (building-* scenarios)");
      // On a building's floor the world has the building's own areas too (first), which the map does not
      // hold, and a building cannot be a floor's plan: the file would not say what the rays see.
      if (is_building)
        throw std::runtime_error("--ceilings-building: the plan is a building (" + plan_file +
                                 "); give one floor's plan file (or give the segmenter the building itself)");
      std::ofstream cb(ceilings_building);
      const std::string pf = plan_file.empty() ? "" : std::filesystem::absolute(plan_file).string();
      cb << fploc::sim::ceiling_map_building_text(sim.ceiling_map(), pf, "0", layers, units);
      if (!cb) throw std::runtime_error(ceilings_building + ": cannot write");
    }
    std::cerr << "fploc sim: path " << sim.motion().length() << " m, " << sim.motion().moving_time() << " s moving, avg "
              << sim.motion().avg_speed() << " m/s, max " << sim.motion().max_speed() << " m/s, " << sim.num_frames()
              << " frames\n";

    lcm::LogFile log(out, "w");
    if (!log.good()) throw std::runtime_error(out + ": cannot open for writing");
    const double t_end = duration > 0 ? o.t0_s + duration : o.t0_s + sim.motion().duration();
    const double period = 1.0 / o.rate_hz;
    std::vector<uint8_t> buf;
    fploc::Trajectory traj;
    std::ofstream floors_csv;
    if (sim.building()) {
      if (gt_floors.empty())
        gt_floors = (gt.size() > 4 && gt.substr(gt.size() - 4) == ".tum" ? gt.substr(0, gt.size() - 4) : gt) + ".floors.csv";
      floors_csv.open(gt_floors);
      if (!floors_csv) throw std::runtime_error(gt_floors + ": cannot open for writing");
      floors_csv << "t,floor_index,floor,state\n";
    }
    fploc::sim::SimScan f;
    fploc::scan_t sm;
    size_t imu_k = 0, imu_dropped = 0;
    int64_t imu_seq = 0;
    const auto& imu = sim.imu();
    int frames = 0, dropped = 0;
    uint64_t drop_state = seed * 2654435761u + 1;
    auto in_gap = [&](double t) {  // t from the sequence's start
      return std::any_of(gap_spans.begin(), gap_spans.end(), [&](const auto& g) { return t >= g.first && t < g.second; });
    };
    auto flush_imu = [&](double until) {
      for (; imu_k < imu.size() && o.t0_s + imu[imu_k].t <= until; ++imu_k) {
        if (gap_imu && in_gap(imu[imu_k].t)) {
          ++imu_dropped;
          continue;
        }
        fploc::imu_t m;
        const int64_t ut = int64_t(std::llround((o.t0_s + imu[imu_k].t) * 1e6));
        m.utime = m.accel_utime = m.gyro_utime = ut;
        m.seq = imu_seq++;
        for (int i = 0; i < 3; ++i) {
          m.accel[i] = imu[imu_k].accel[i];
          m.gyro[i] = imu[imu_k].gyro[i];
        }
        m.source = "sim";
        write_event(log, ut, "OS1_IMU", m, buf);
      }
    };
    // The frames written (--duration cuts the path short): the progress counted against the whole path's frames
    // ("frame 600/6015", then "wrote 600 scans").
    int to_write = 0;
    while (to_write < sim.num_frames() && sim.frame_time(to_write) + period <= t_end + 1e-9) ++to_write;
    for (int k = 0; k < sim.num_frames(); ++k) {
      const double ts = sim.frame_time(k);
      if (ts + period > t_end + 1e-9) break;
      sim.frame(k, f);
      // Ground truth at the scan's first column time (published when the sweep starts).
      flush_imu(ts);
      const fploc::StampedPose p = sim.ground_truth(f.scan.utime * 1e-6);
      const fploc::ground_truth_t g =
          fploc::adapters::ground_truth_msg(f.scan.utime, k, p, sim.velocity(p.t), sim.angular_velocity(p.t), scenario);
      write_event(log, g.utime, "FPLOC_GROUND_TRUTH", g, buf);
      traj.push_back(p);
      if (floors_csv.is_open()) {
        const int fl = sim.floor_at(p.t);
        char line[160];
        std::snprintf(line, sizeof line, "%.6f,%d,%s,%s\n", p.t, fl, sim.floor_name(fl).c_str(), sim.state_at(p.t).c_str());
        floors_csv << line;
      }
      // The scan is complete at the end of its sweep.
      const double t_pub = ts + period;
      flush_imu(t_pub);
      drop_state = drop_state * 6364136223846793005ull + 1442695040888963407ull;
      if (in_gap(ts - o.t0_s) || (drop_scans > 0 && double(drop_state >> 11) / double(1ull << 53) < drop_scans)) {
        ++dropped;  // lost on the way: ground truth and IMU stay
      } else {
        fploc::adapters::to_msg(f.scan, sm);
        write_event(log, int64_t(std::llround(t_pub * 1e6)), "OS1_SCAN", sm, buf);
      }
      ++frames;
      if (frames % 100 == 0) std::cerr << "\r  frame " << frames << "/" << to_write << std::flush;
    }
    flush_imu(t_end);
    std::cerr << "\n";
    fploc::write_tum(gt, traj);
    if (floors_csv.is_open()) {
      floors_csv.close();
      if (!floors_csv) throw std::runtime_error(gt_floors + ": cannot write");
      std::cerr << "fploc sim: ground-truth floor per scan written to " << gt_floors << "\n";
    }
    std::string truth_path;
    if (const auto* edit = sim.world_edit()) {
      truth_path = !truth.empty() ? truth
                   : (out.size() > 4 && out.substr(out.size() - 4) == ".lcm" ? out.substr(0, out.size() - 4) : out) + ".world.json";
      const fploc::FloorPlan& plan_used = plan.elements.empty() ? (scenario.rfind("corridor", 0) == 0 ? fploc::sim::demo_corridor_plan()
                                                                                               : fploc::sim::demo_room_plan())
                                                                : plan;
      std::ofstream tf(truth_path);
      // Plus the static clutter the simulator put in (furniture, cabinets): unmapped, but not the building.
      nlohmann::json tj = nlohmann::json::parse(edit->truth_json(plan_used));
      auto& fj = tj["furniture"] = nlohmann::json::array();
      for (const auto& f : sim.world().furniture())
        fj.push_back({{"c", {f.center.x(), f.center.y()}}, {"yaw", f.yaw}, {"half", {f.half.x(), f.half.y()}}, {"height", f.z1}});
      tj["people"] = sim.world().people().size();
      tf << fploc::json_text(tj, 1) << "\n";
      if (!tf) throw std::runtime_error(truth_path + ": cannot write the world truth");
      std::cerr << "fploc sim: world-vs-plan truth written to " << truth_path << "\n";
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    const double simulated = frames * period;
    if (dropped) std::cerr << "fploc sim: " << dropped << " of " << frames << " scans dropped (--drop-scans, --gap)\n";
    std::cerr << "fploc sim: wrote " << frames - dropped << " scans, " << imu_k - imu_dropped << " IMU samples to " << out << " in " << wall
              << " s (" << simulated / std::max(wall, 1e-9) << "x real time)\n";
    if (json) {
      nlohmann::json j;
      j["scenario"] = scenario;
      j["seed"] = seed;
      j["frames"] = frames;
      j["scans_dropped"] = dropped;
      j["imu_samples"] = imu_k - imu_dropped;
      j["length_m"] = sim.motion().length();
      j["avg_speed_mps"] = sim.motion().avg_speed();
      j["max_speed_mps"] = sim.motion().max_speed();
      j["duration_s"] = sim.motion().duration();
      j["beams"] = sim.beam_source();
      j["wall_s"] = wall;
      j["realtime_factor"] = simulated / std::max(wall, 1e-9);
      if (!truth_path.empty()) j["world_truth"] = truth_path;
      if (sim.building()) {
        j["gt_floors"] = gt_floors;
        j["start_floor"] = sim.floor_name(sim.floor_at(o.t0_s));
        j["t0"] = o.t0_s;
        auto& fl = j["floors"] = nlohmann::json::array();
        for (const auto& f : sim.building()->floors) fl.push_back({{"name", f.name}, {"elevation_m", f.elevation}});
        auto& ch = j["floor_changes"] = nlohmann::json::array();
        for (const auto& c : sim.floor_changes())
          ch.push_back({{"t", o.t0_s + c.t}, {"from", sim.floor_name(c.from)}, {"to", sim.floor_name(c.to)}, {"how", c.how}});
      }
      std::cout << fploc::json_text(j) << std::endl;
    }
  } catch (const std::exception& e) {
    std::cerr << "fploc sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
