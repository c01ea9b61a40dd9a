// fploc bench perception [--plan FILE [--layers G,..] [--units U]] --scenario NAME [--seed N] [--beams B] [--imu] [--json]
// Simulates the sequence (modules/sim, no LCM) and runs the paper's segmenter, the PCL RANSAC segmenter
// and the feature extractor on every scan (every --stride-th). Errors are against the simulator's ground
// truth at the middle of each sweep (the sensor wobbles during the 0.1 s sweep; without --imu the plane
// fit sees the whole sweep as measured, with --imu the gyro de-skews it to mid-sweep). Accuracy keys:
// median, p95 and max over the frames with a ceiling, and "all_frames": the same over every frame as
// published (fallbacks included), with the longest run of frames whose height error exceeds 5 cm.
#include <CLI/CLI.hpp>
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "fploc/core/text_out.h"
#include "fploc/features/features.h"
#include "fploc/floorplan/io.h"
#include "fploc/segmentation/ransac_segmenter.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"
#include "fploc/runtime/cli_messages.h"

namespace {

constexpr double kDeg = M_PI / 180.0;

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// q-quantile (nearest rank) and maximum.
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  const size_t k = std::min(v.size() - 1, size_t(std::ceil(q * double(v.size()))) - (q > 0 ? 1 : 0));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}
double max_of(const std::vector<double>& v) { return v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end()); }

struct Acc {
  int frames = 0, found = 0;
  std::vector<double> roll, pitch, z;              // frames with a ceiling
  std::vector<double> roll_all, pitch_all, z_all;  // every frame, whatever the segmenter published
  int longest_z_block = 0, run = 0;                // consecutive frames with |z err| > 5 cm
  size_t selected = 0, selected_bad = 0, plan_walls = 0, plan_kept = 0;
  double us = 0;

  void add(const fploc::seg::Segmentation& s, const fploc::sim::SimScan& f, const fploc::StampedPose& gt, double us_scan) {
    ++frames;
    us += us_scan;
    const Eigen::Vector3d rpy = gt.rpy();
    const double er = std::abs(std::remainder(s.roll - rpy[0], 2 * M_PI)) / kDeg;
    const double ep = std::abs(std::remainder(s.pitch - rpy[1], 2 * M_PI)) / kDeg;
    const double ez = std::abs(s.z - gt.p.z());
    if (s.ceiling.found) {
      ++found;
      roll.push_back(er);
      pitch.push_back(ep);
      z.push_back(ez);
    }
    if (s.attitude_source != fploc::seg::AttitudeSource::kNone) {
      roll_all.push_back(er);
      pitch_all.push_back(ep);
      z_all.push_back(ez);
    }
    run = ez > 0.05 ? run + 1 : 0;
    longest_z_block = std::max(longest_z_block, run);
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
  static void stats(nlohmann::json& j, const std::string& key, const std::vector<double>& v) {
    j[key + "_median"] = median(v);
    j[key + "_p95"] = quantile(v, 0.95);
    j[key + "_max"] = max_of(v);
  }
  nlohmann::json json() const {
    nlohmann::json j;
    j["frames"] = frames;
    j["ceiling_found"] = frames ? double(found) / frames : 0.0;
    stats(j, "roll_err_deg", roll);
    stats(j, "pitch_err_deg", pitch);
    stats(j, "z_err_m", z);
    nlohmann::json all;  // what downstream gets in every frame (fallbacks included)
    all["frames"] = z_all.size();
    stats(all, "roll_err_deg", roll_all);
    stats(all, "pitch_err_deg", pitch_all);
    stats(all, "z_err_m", z_all);
    all["longest_block_z_err_over_5cm"] = longest_z_block;
    j["all_frames"] = all;
    j["wall_point_precision"] = selected ? 1.0 - double(selected_bad) / selected : 0.0;
    j["wall_point_recall"] = plan_walls ? double(plan_kept) / plan_walls : 0.0;
    return j;
  }
};

// Least-squares plane through points, normal oriented like `ref` (false with < 3 points).
bool ls_plane(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3d& ref, Eigen::Vector4d& out) {
  if (pts.size() < 3) return false;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (const auto& q : pts) m += q.cast<double>();
  m /= double(pts.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& q : pts) C += (q.cast<double>() - m) * (q.cast<double>() - m).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  Eigen::Vector3d n = es.eigenvectors().col(0);
  if (n.dot(ref) < 0) n = -n;
  out << n, -n.dot(m);
  return true;
}

// --diagnose: why a frame was rejected or is off. The upper-half returns (top half of the beams by altitude)
// against the true ceiling plane at mid-sweep and against the segmenter's plane (inliers within 5 cm by
// simulator label, returns more than 10 cm beyond), and least-squares planes through the ceiling-labelled
// returns as measured, de-skewed with the true poses, and as the segmenter saw them (its de-skew).
void diagnose_frame(int k, const fploc::sim::Simulator& sim, const fploc::sim::SimScan& f, const fploc::StampedPose& gt,
                    const fploc::seg::Segmentation& s, const std::vector<Eigen::Vector3f>& seg_pts) {
  static fploc::XyzLut lut;
  const auto& sc = f.scan;
  if (lut.height != sc.height || lut.width != sc.width) lut = fploc::make_xyz_lut(sc.beams, sc.width);
  std::vector<double> sorted = sc.beams.altitude_deg;
  std::sort(sorted.begin(), sorted.end());
  const double alt_mid = sorted[sorted.size() / 2];
  const Eigen::Matrix3d R = gt.q.toRotationMatrix();
  const Eigen::Isometry3d Tmid_inv = gt.iso().inverse();
  std::vector<double> hz;
  std::vector<Eigen::Vector3f> pts, ceil_raw, ceil_true, ceil_seg;
  std::vector<uint8_t> lab;
  for (int u = 0; u < sc.height; ++u) {
    if (sc.beams.altitude_deg[u] < alt_mid) continue;
    for (int v = 0; v < sc.width; ++v) {
      const size_t i = size_t(u) * sc.width + v;
      if (sc.range_mm[i] < 400) continue;
      const Eigen::Vector3f p = fploc::lut_point(lut, u, sc.measurement_id[v], sc.range_mm[i]);
      pts.push_back(p);
      lab.push_back(f.label[i]);
      if (f.label[i] != uint8_t(fploc::sim::Label::kCeiling)) continue;
      hz.push_back((R * p.cast<double>()).z() + gt.p.z());
      ceil_raw.push_back(p);
      const Eigen::Isometry3d Tc = sim.ground_truth(double(sc.column_utime[v]) * 1e-6).iso();
      ceil_true.push_back(((Tmid_inv * Tc) * p.cast<double>()).cast<float>());
      if (i < seg_pts.size()) ceil_seg.push_back(seg_pts[i]);
    }
  }
  // True ceiling: world plane z = h, h = median world height of the ceiling-labelled returns.
  const double h = median(hz);
  Eigen::Vector4d truth;
  truth << R.transpose() * Eigen::Vector3d(0, 0, -1), h - gt.p.z();
  const Eigen::Vector3d rpy = gt.rpy();
  auto eval = [&](const Eigen::Vector4d& pl, const std::string& name) {
    int inl = 0, beyond = 0, by_label[6] = {0};
    for (size_t j = 0; j < pts.size(); ++j) {
      const double r = pl.head<3>().dot(pts[j].cast<double>()) + pl[3];
      if (std::abs(r) < 0.05) {
        ++inl;
        ++by_label[std::min<int>(5, lab[j])];
      }
      beyond += r < -0.10;
    }
    double roll, pitch;
    fploc::seg::roll_pitch_from_up(-pl.head<3>(), roll, pitch);
    std::cerr << "    " << name << ": d " << pl[3] << " err roll " << std::remainder(roll - rpy[0], 2 * M_PI) / kDeg
              << " pitch " << std::remainder(pitch - rpy[1], 2 * M_PI) / kDeg << " deg; inliers " << inl << " (floor "
              << by_label[1] << " ceiling " << by_label[2] << " wall " << by_label[3] << " pillar " << by_label[4]
              << " clutter " << by_label[5] << "), beyond " << beyond << "\n";
  };
  std::cerr << "diagnose frame " << k << ": " << pts.size() << " upper returns, " << hz.size()
            << " ceiling-labelled (median height " << h << " m), status '" << s.status_text << "'\n";
  eval(truth, "true plane");
  eval(s.ceiling.coeffs, std::string("segmenter") + (s.deskewed ? " (de-skewed)" : ""));
  Eigen::Vector4d pl;
  if (ls_plane(ceil_raw, truth.head<3>(), pl)) eval(pl, "LS ceiling-labelled, as measured");
  if (ls_plane(ceil_true, truth.head<3>(), pl)) eval(pl, "LS ceiling-labelled, de-skewed with true poses");
  if (s.deskewed && ls_plane(ceil_seg, truth.head<3>(), pl)) eval(pl, "LS ceiling-labelled, segmenter's de-skew");
}

std::string shared_dir() {
  if (const char* e = std::getenv("FPLOC_SHARED_DIR")) return e;
  return FPLOC_SHARED_DIR;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fploc bench perception: segmentation and feature accuracy/speed on a simulated sequence"};
  fploc::rt::install_cli_messages(app, "fploc bench perception");
  std::string plan_file, units, scenario, beams;
  std::vector<std::string> layers;
  uint64_t seed = 0;
  int max_frames = 0, stride = 1;
  bool json = false, no_clutter = false, no_patches = false, verbose = false, diagnose = false;
  double noise = 0.02;
  bool imu_prior = false, imu = false;
  fploc::seg::SegmenterConfig cfg;  // defaults: nothing known about the room
  app.add_option("--plan", plan_file, "floor plan (.dxf/.csv/.json/.fpmap); default: the scenario's demo plan");
  app.add_option("--layers", layers, "layer globs")->delimiter(',');
  app.add_option("--units", units, "m|cm|mm override");
  app.add_option("--scenario", scenario, "scenario name (e.g. room-small-loop-medium)")->required();
  app.add_option("--seed", seed, "random seed");
  app.add_option("--beams", beams, "beam pattern: os1-64 (default), os1-32, os1-128, vlp16 (fploc sim --beams)");
  app.add_option("--max-frames", max_frames, "stop after this many evaluated frames (0 = all)");
  app.add_option("--stride", stride, "evaluate every k-th frame");
  app.add_option("--noise", noise, "range noise sigma [m]");
  app.add_flag("--no-clutter", no_clutter, "no furniture or people");
  app.add_flag("--no-ceiling-patches", no_patches, "flat ceiling everywhere");
  app.add_flag("--imu", imu, "feed the simulated IMU samples of each sweep (gyro de-skew of the rotation)");
  app.add_flag("--imu-prior", imu_prior, "--imu and use its gravity as prior (use_imu_prior)");
  app.add_option("--ceiling-height", cfg.ceiling_height_m, "known floor-to-ceiling height [m] (0 = estimated)");
  app.add_option("--irls-initial-scale", cfg.irls_initial_scale_m, "first Tukey cut-off [m]");
  app.add_option("--seed-triplets", cfg.seed_triplets, "planes through seed triplets tried as start");
  app.add_flag("--json", json, "JSON on stdout");
  app.add_flag("--verbose", verbose, "one line per frame on stderr");
  app.add_flag("--diagnose", diagnose, "for frames without a ceiling: what the true ceiling plane would score");
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
    o.beams = beams;
    fploc::sim::Simulator sim(std::move(plan), o);
    std::cerr << "bench perception: " << scenario << " seed " << seed << ", " << sim.num_frames()
              << " frames, beams: " << sim.beam_source() << "\n";

    cfg.use_imu_prior = imu_prior;
    fploc::seg::RingSegmenter rings(cfg);
    // A twin without per-pixel labels (they cost time and exist only for this bench): same inputs, same
    // results, and its CPU time is what the node spends.
    fploc::seg::RingSegmenter rings_timed(cfg);
    fploc::feat::FeatureExtractor fx_timed;
    fploc::seg::RansacSegmenter ransac(cfg);
    rings.set_keep_labels(true);
    ransac.set_keep_labels(true);
    fploc::feat::FeatureExtractor fx;
    Acc acc_rings, acc_ransac;
    double us_features = 0;
    std::vector<double> cpu_seg, cpu_feat, cpu_ransac;
    double imu_fed_until = -1e300;
    std::map<std::string, Acc> by_region;  // the paper segmenter's accuracy by sensor position
    auto cpu_us = [] {
      timespec ts{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
      return double(ts.tv_sec) * 1e6 + double(ts.tv_nsec) * 1e-3;
    };
    size_t n_features = 0, n_groups = 0;
    fploc::sim::SimScan f;
    using clk = std::chrono::steady_clock;
    auto us_since = [](clk::time_point t) { return std::chrono::duration<double, std::micro>(clk::now() - t).count(); };
    int done = 0;
    for (int k = 0; k < sim.num_frames(); k += std::max(1, stride)) {
      if (max_frames > 0 && done >= max_frames) break;
      sim.frame(k, f);
      if (imu || imu_prior) {
        // The IMU stream up to the end of this sweep, as a node receives it (every sample once, also those
        // between evaluated frames with --stride).
        const double tb = sim.frame_time(k) - o.t0_s + 1.0 / o.rate_hz;
        for (const auto& smp : sim.imu())
          if (smp.t > imu_fed_until && smp.t < tb) {
            imu_fed_until = smp.t;
            rings.add_accel(smp.accel);
            rings_timed.add_accel(smp.accel);
            ransac.add_accel(smp.accel);
            const int64_t ut = int64_t(std::llround((o.t0_s + smp.t) * 1e6));
            rings.add_gyro(smp.gyro, ut);
            rings_timed.add_gyro(smp.gyro, ut);
            ransac.add_gyro(smp.gyro, ut);
          }
      }
      const fploc::StampedPose gt = sim.ground_truth(sim.frame_time(k) + 0.5 / o.rate_hz);
      // Timed (wall clock and thread CPU): the label-free twin and the features on its output.
      auto t0 = clk::now();
      double c0 = cpu_us();
      const auto& st = rings_timed.process(f.scan);
      const double us_seg = us_since(t0);
      cpu_seg.push_back(cpu_us() - c0);
      t0 = clk::now();
      c0 = cpu_us();
      const size_t n_feat_timed = fx_timed.process(st).size();
      us_features += us_since(t0);
      cpu_feat.push_back(cpu_us() - c0);
      // Accuracy: the labelled segmenter (identical planes and wall points).
      const auto& s = rings.process(f.scan);
      const auto& ft = fx.process(s);
      if (ft.size() != n_feat_timed || st.wall.size() != s.wall.size())
        throw std::runtime_error("segmenter with labels differs from the one without (frame " + std::to_string(k) + ")");
      n_features += ft.size();
      n_groups += ft.num_groups;
      acc_rings.add(s, f, gt, us_seg);
      {
        // Where the sensor is: under the missing (open) or the sloped ceiling patch of the simulator, or not.
        std::string where = "flat_ceiling";
        for (const auto& pt : sim.world().ceiling_patches()) {
          const Eigen::Vector2d q = gt.p.head<2>();
          if ((q.array() >= pt.box.min.array()).all() && (q.array() <= pt.box.max.array()).all())
            where = pt.open ? "under_open_patch" : "under_sloped_patch";
        }
        by_region[where].add(s, f, gt, us_seg);
      }
      t0 = clk::now();
      c0 = cpu_us();
      const auto& r = ransac.process(f.scan);
      acc_ransac.add(r, f, gt, us_since(t0));
      cpu_ransac.push_back(cpu_us() - c0);
      if (verbose)
        std::cerr << "  ransac " << fploc::seg::to_string(r.status) << " d " << r.ceiling.distance() << " inl "
                  << r.ceiling.inliers << " beyond " << r.ceiling.beyond << " '" << r.status_text << "'\n";
      ++done;
      if (verbose) {
        const Eigen::Vector3d rpy = gt.rpy();
        std::cerr << "frame " << k << " gt z " << gt.p.z() << " roll " << rpy[0] / kDeg << " pitch " << rpy[1] / kDeg
                  << " | rings " << fploc::seg::to_string(s.status) << " c " << s.ceiling.found << " d "
                  << s.ceiling.distance() << " inl " << s.ceiling.inliers << " rms " << s.ceiling.rms_m << " beyond " << s.ceiling.beyond << " g " << s.ground.found << " d "
                  << s.ground.distance() << " inl " << s.ground.inliers << " H " << rings.room_height() << " z " << s.z
                  << " roll " << s.roll / kDeg << " pitch " << s.pitch / kDeg << " | err roll "
                  << std::remainder(s.roll - rpy[0], 2 * M_PI) / kDeg << " pitch "
                  << std::remainder(s.pitch - rpy[1], 2 * M_PI) / kDeg << " z " << s.z - gt.p.z() << " '"
                  << s.status_text << "'\n";
      }
      if (diagnose && (!s.ceiling.found || std::abs(s.z - gt.p.z()) > 0.01 ||
                       std::abs(std::remainder(s.roll - gt.rpy()[0], 2 * M_PI)) > 0.1 * kDeg ||
                       std::abs(std::remainder(s.pitch - gt.rpy()[1], 2 * M_PI)) > 0.1 * kDeg))
        diagnose_frame(k, sim, f, gt, s, rings.points());
      if (!json && done % 50 == 0) std::cerr << "  frame " << k << "\n";
    }
    nlohmann::json out = acc_rings.json();
    const int n = std::max(1, acc_rings.frames);
    out["us_per_scan"] = {{"segmenter", acc_rings.us / n}, {"features", us_features / n},
                          {"segmenter_ransac", acc_ransac.us / n}};
    // Thread CPU time (less sensitive to other processes on a shared machine than the wall clock above).
    auto cpu_stats = [](const std::vector<double>& v) {
      double sum = 0;
      for (double x : v) sum += x;
      return nlohmann::json{{"mean", v.empty() ? 0.0 : sum / double(v.size())}, {"median", median(v)},
                            {"p95", quantile(v, 0.95)}, {"max", max_of(v)}};
    };
    std::vector<double> both(cpu_seg.size());
    for (size_t i = 0; i < both.size(); ++i) both[i] = cpu_seg[i] + cpu_feat[i];
    out["cpu_us_per_scan"] = {{"segmenter", cpu_stats(cpu_seg)}, {"features", cpu_stats(cpu_feat)},
                              {"segmenter_plus_features", cpu_stats(both)}, {"segmenter_ransac", cpu_stats(cpu_ransac)}};
    out["ransac"] = acc_ransac.json();
    for (const auto& [where, acc] : by_region) out["by_sensor_position"][where] = acc.json();
    out["features_per_scan"] = double(n_features) / n;
    out["groups_per_scan"] = double(n_groups) / n;
    out["scenario"] = scenario;
    out["beams"] = beams.empty() ? "os1-64" : beams;
    out["beam_source"] = sim.beam_source();
    out["imu"] = imu || imu_prior;
    out["imu_prior"] = imu_prior;
    if (imu || imu_prior)
      out["gyro_bias_estimate_rad_s"] = {rings.gyro_bias().x(), rings.gyro_bias().y(), rings.gyro_bias().z()};
    out["seed"] = seed;
    if (json) {
      std::cout << fploc::json_text(out, 2) << "\n";
    } else {
      std::cerr << fploc::json_text(out, 2) << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fploc bench perception: " << e.what() << "\n";
    return 1;
  }
}
