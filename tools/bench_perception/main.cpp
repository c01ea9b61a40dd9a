// fploc bench perception [--plan FILE [--layers G,..] [--units U]] --scenario NAME [--seed N] [--json]
// Simulates the sequence (modules/sim, no LCM) and runs the paper's segmenter, the PCL RANSAC segmenter
// and the feature extractor on every scan. Errors are against the simulator's ground truth at the middle
// of each sweep (the sensor wobbles during the 0.1 s sweep; the plane fit sees the whole sweep).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "fploc/features/features.h"
#include "fploc/floorplan/io.h"
#include "fploc/segmentation/ransac_segmenter.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"

namespace {

constexpr double kDeg = M_PI / 180.0;

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct Acc {
  int frames = 0, found = 0;
  std::vector<double> roll, pitch, z;
  size_t selected = 0, selected_bad = 0, plan_walls = 0, plan_kept = 0;
  double us = 0;

  void add(const fploc::seg::Segmentation& s, const fploc::sim::SimScan& f, const fploc::StampedPose& gt, double us_scan) {
    ++frames;
    us += us_scan;
    if (s.ceiling.found) {
      ++found;
      const Eigen::Vector3d rpy = gt.rpy();
      roll.push_back(std::abs(std::remainder(s.roll - rpy[0], 2 * M_PI)) / kDeg);
      pitch.push_back(std::abs(std::remainder(s.pitch - rpy[1], 2 * M_PI)) / kDeg);
      z.push_back(std::abs(s.z - gt.p.z()));
    }
    using L = fploc::sim::Label;
    for (size_t i = 0; i < f.label.size() && i < s.label.size(); ++i) {
      const L t = L(f.label[i]);
      const bool wall = s.label[i] == 3;
      if (wall) {
        ++selected;
        selected_bad += t == L::kFloor || t == L::kCeiling;
      }
      if (t == L::kWall || t == L::kPillar) {
        ++plan_walls;
        plan_kept += wall;
      }
    }
  }
  nlohmann::json json() const {
    nlohmann::json j;
    j["frames"] = frames;
    j["ceiling_found"] = frames ? double(found) / frames : 0.0;
    j["roll_err_deg_median"] = median(roll);
    j["pitch_err_deg_median"] = median(pitch);
    j["z_err_m_median"] = median(z);
    j["wall_point_precision"] = selected ? 1.0 - double(selected_bad) / selected : 0.0;
    j["wall_point_recall"] = plan_walls ? double(plan_kept) / plan_walls : 0.0;
    return j;
  }
};

std::string shared_dir() {
  if (const char* e = std::getenv("FPLOC_SHARED_DIR")) return e;
  return FPLOC_SHARED_DIR;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc bench perception: segmentation and feature accuracy/speed on a simulated sequence"};
  std::string plan_file, units, scenario;
  std::vector<std::string> layers;
  uint64_t seed = 0;
  int max_frames = 0, stride = 1;
  bool json = false, no_clutter = false, no_patches = false, verbose = false;
  double noise = 0.02;
  app.add_option("--plan", plan_file, "floor plan (.dxf/.csv/.json/.fpmap); default: the scenario's demo plan");
  app.add_option("--layers", layers, "layer globs")->delimiter(',');
  app.add_option("--units", units, "m|cm|mm override");
  app.add_option("--scenario", scenario, "scenario name (e.g. room-small-loop-medium)")->required();
  app.add_option("--seed", seed, "random seed");
  app.add_option("--max-frames", max_frames, "stop after this many evaluated frames (0 = all)");
  app.add_option("--stride", stride, "evaluate every k-th frame");
  app.add_option("--noise", noise, "range noise sigma [m]");
  app.add_flag("--no-clutter", no_clutter, "no furniture or people");
  app.add_flag("--no-ceiling-patches", no_patches, "flat ceiling everywhere");
  app.add_flag("--json", json, "JSON on stdout");
  app.add_flag("--verbose", verbose, "one line per frame on stderr");
  CLI11_PARSE(app, argc, argv);
  try {
    fploc::FloorPlan plan;
    if (!plan_file.empty()) plan = fploc::load_floor_plan(plan_file, layers, units);
    fploc::sim::SimulatorOptions o;
    o.scenario = scenario;
    o.seed = seed;
    o.clutter = !no_clutter;
    o.ceiling_patches = !no_patches;
    o.range_noise_m = noise;
    o.shared_dir = shared_dir();
    fploc::sim::Simulator sim(std::move(plan), o);
    std::cerr << "bench perception: " << scenario << " seed " << seed << ", " << sim.num_frames()
              << " frames, beams: " << sim.beam_source() << "\n";

    fploc::seg::SegmenterConfig cfg;  // defaults: nothing known about the room
    fploc::seg::RingSegmenter rings(cfg);
    fploc::seg::RansacSegmenter ransac(cfg);
    rings.set_keep_labels(true);
    ransac.set_keep_labels(true);
    fploc::feat::FeatureExtractor fx;
    Acc acc_rings, acc_ransac;
    double us_features = 0;
    size_t n_features = 0, n_groups = 0;
    fploc::sim::SimScan f;
    using clk = std::chrono::steady_clock;
    auto us_since = [](clk::time_point t) { return std::chrono::duration<double, std::micro>(clk::now() - t).count(); };
    int done = 0;
    for (int k = 0; k < sim.num_frames(); k += std::max(1, stride)) {
      if (max_frames > 0 && done >= max_frames) break;
      sim.frame(k, f);
      const fploc::StampedPose gt = sim.ground_truth(sim.frame_time(k) + 0.5 / o.rate_hz);
      auto t0 = clk::now();
      const auto& s = rings.process(f.scan);
      const double us_seg = us_since(t0);
      t0 = clk::now();
      const auto& ft = fx.process(s);
      us_features += us_since(t0);
      n_features += ft.size();
      n_groups += ft.num_groups;
      acc_rings.add(s, f, gt, us_seg);
      t0 = clk::now();
      const auto& r = ransac.process(f.scan);
      acc_ransac.add(r, f, gt, us_since(t0));
      ++done;
      if (verbose) {
        const Eigen::Vector3d rpy = gt.rpy();
        std::cerr << "frame " << k << " gt z " << gt.p.z() << " roll " << rpy[0] / kDeg << " pitch " << rpy[1] / kDeg
                  << " | rings " << fploc::seg::to_string(s.status) << " c " << s.ceiling.found << " d "
                  << s.ceiling.distance() << " inl " << s.ceiling.inliers << " g " << s.ground.found << " d "
                  << s.ground.distance() << " inl " << s.ground.inliers << " H " << rings.room_height() << " z " << s.z
                  << " roll " << s.roll / kDeg << " pitch " << s.pitch / kDeg << " '" << s.status_text << "'\n";
      }
      if (!json && done % 50 == 0) std::cerr << "  frame " << k << "\n";
    }
    nlohmann::json out = acc_rings.json();
    const int n = std::max(1, acc_rings.frames);
    out["us_per_scan"] = {{"segmenter", acc_rings.us / n}, {"features", us_features / n},
                          {"segmenter_ransac", acc_ransac.us / n}};
    out["ransac"] = acc_ransac.json();
    out["features_per_scan"] = double(n_features) / n;
    out["groups_per_scan"] = double(n_groups) / n;
    out["scenario"] = scenario;
    out["seed"] = seed;
    if (json) {
      std::cout << out.dump(2) << "\n";
    } else {
      std::cerr << out.dump(2) << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fploc bench perception: " << e.what() << "\n";
    return 1;
  }
}
