// fploc-ndt: the NDT peer (modules/ndt, the hdl_localization approach) as a drop-in for matcher + optimizer:
// the segmenter's wall points (FPLOC_SEGMENTS, what hdl_localization's downsampled cloud corresponds to)
// and the IMU's gyro (OS1_IMU) in, pose_t out on FPLOC_POSE (x, y, yaw from NDT with their covariance
// from the NDT Hessian; roll, pitch, z and their sigmas from the segmenter; status OK / POOR / LOST).
// Roll/pitch/z the segmenter marks unknown (its sigmas) are replaced by the last known ones, as the
// matcher does. Deterministic for its input messages (no wall clock in outputs): `fploc replay` stays
// reproducible; the thread CPU time per scan goes to stderr and the optional stats file.
#include <fploc/imu_t.hpp>
#include <fploc/pose_t.hpp>
#include <fploc/segments_t.hpp>
#include <time.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "fploc/config/floor_ref.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/io.h"
#include "fploc/matcher/imu_yaw.h"
#include "fploc/ndt/ndt_localizer.h"
#include "fploc/runtime/node.h"
#include "options/ndt.pb.h"

namespace {

namespace nd = fploc::ndt;

double thread_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e6 + double(ts.tv_nsec) * 1e-3;
}

nd::Config config_of(const fploc::NdtOptions& o) {
  nd::Config c;
  if (o.has_resolution_m()) c.resolution_m = o.resolution_m();
  if (o.has_step_size_m()) c.step_size_m = o.step_size_m();
  if (o.has_epsilon()) c.epsilon = o.epsilon();
  if (o.has_max_iterations()) c.max_iterations = o.max_iterations();
  if (o.has_leaf_m()) c.leaf_m = o.leaf_m();
  if (o.has_map_z_min_m()) c.map.z_min_m = o.map_z_min_m();
  if (o.has_map_z_max_m()) c.map.z_max_m = o.map_z_max_m();
  if (o.has_map_spacing_m()) c.map.spacing_m = o.map_spacing_m();
  if (o.has_inlier_distance_m()) c.inlier_distance_m = o.inlier_distance_m();
  if (o.has_ok_inlier_ratio()) c.ok_inlier_ratio = o.ok_inlier_ratio();
  if (o.has_poor_sigma_m()) c.poor_sigma_m = o.poor_sigma_m();
  if (o.has_lost_after()) c.lost_after = o.lost_after();
  return c;
}

class NdtNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"ndt", "ndt", "NDT peer (hdl_localization approach, PCL NDT) against the extruded floor plan",
            // Live, a scan that waited is stale: a node slower than the scans takes the newest (the
            // prediction spans the gap with the IMU and dt); `fploc replay` still gets every scan.
            {fploc::rt::input<fploc::segments_t>("segments", "FPLOC_SEGMENTS", fploc::rt::Queue::kLatest),
             fploc::rt::input<fploc::imu_t>("imu", "OS1_IMU"),
             fploc::rt::output<fploc::pose_t>("pose", "FPLOC_POSE")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::NdtOptions>();
    if (o.plan().file().empty()) throw std::runtime_error("ndt.plan.file: no floor plan given");
    if (!o.has_initial_pose()) throw std::runtime_error("ndt.initial_pose: required (NDT tracks from a known start)");
    const std::vector<std::string> layers(o.plan().layers().begin(), o.plan().layers().end());
    const fploc::FloorPlan plan = fploc::load_floor_plan(ctx.resolve_path(o.plan().file()), layers, o.plan().units());
    floor_ = fploc::config::floor_ref(o.plan(), ctx.resolve_path(o.plan().file()));
    try {
      loc_ = std::make_unique<nd::Localizer>(plan, config_of(o));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("ndt options: ") + e.what());
    }
    loc_->set_pose(o.initial_pose().x(), o.initial_pose().y(), o.initial_pose().yaw());
    use_imu_ = !o.ignore_imu();
    stats_file_ = o.stats_file();
    const auto& c = loc_->config();
    std::cerr << "[" << ctx.name() << "] " << plan.elements.size() << " plan elements -> " << loc_->map_points()
              << " map points (" << c.map.z_min_m << ".." << c.map.z_max_m << " m, every " << c.map.spacing_m
              << " m); NDT resolution " << c.resolution_m << " m, step " << c.step_size_m << ", epsilon " << c.epsilon
              << ", " << c.max_iterations << " iterations, leaf " << c.leaf_m << " m, IMU " << (use_imu_ ? "on" : "off") << "\n";
    out_ = ctx.advertise<fploc::pose_t>("pose");
    ctx.subscribe<fploc::imu_t>("imu", [this](const fploc::imu_t& m) {
      if (use_imu_) imu_.add(m.utime, m.gyro[2]);
    });
    ctx.subscribe<fploc::segments_t>("segments", [this](const fploc::segments_t& m) { on_segments(m); });
  }

  void shutdown() override {
    if (done_) return;
    done_ = true;
    std::vector<double> c = cpu_us_;
    std::sort(c.begin(), c.end());
    auto pct = [&](double q) { return c.empty() ? 0.0 : c[std::min(c.size() - 1, size_t(q * double(c.size())))]; };
    const double mean = scans_ ? cpu_total_us_ / double(scans_) : 0.0;
    std::cerr << "[" << ctx_->name() << "] " << scans_ << " scans: " << counts_[0] << " OK, " << counts_[1] << " POOR, "
              << counts_[2] << " LOST; " << mean << " us thread CPU per scan (" << pct(0.5) << " p50, " << pct(0.99)
              << " p99); " << (scans_ ? double(iterations_) / double(scans_) : 0.0) << " NDT iterations per scan\n";
    if (!stats_file_.empty()) {
      nlohmann::json j{{"node", ctx_->name()},
                       {"scans", scans_},
                       {"ok", counts_[0]},
                       {"poor", counts_[1]},
                       {"lost", counts_[2]},
                       {"cpu_us_per_scan_mean", mean},
                       {"cpu_us_per_scan_p50", pct(0.5)},
                       {"cpu_us_per_scan_p99", pct(0.99)},
                       {"iterations_per_scan", scans_ ? double(iterations_) / double(scans_) : 0.0},
                       {"points_per_scan", scans_ ? double(points_) / double(scans_) : 0.0}};
      std::ofstream f(stats_file_);
      if (f) f << fploc::json_text(j, 1) << "\n";
      else ctx_->error("stats_file '" + stats_file_ + "': cannot write");
    }
  }

 private:
  void on_segments(const fploc::segments_t& m) {
    const double t0 = thread_cpu_us();
    if (have_prev_ && m.utime <= prev_utime_) {
      ctx_->error("segments seq " + std::to_string(m.seq) + ": utime " + std::to_string(m.utime) + " not after the previous scan's (ignored)");
      return;
    }
    nd::Scan s;
    s.t = double(m.utime) * 1e-6;
    const size_t n = size_t(std::max(0, m.num_points));
    if (m.x.size() < n || m.y.size() < n || m.z_pts.size() < n) {
      ctx_->error("segments seq " + std::to_string(m.seq) + ": fewer point coordinates than num_points (ignored)");
      return;
    }
    s.points.reserve(n);
    int dropped = 0;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f p(m.x[i], m.y[i], m.z_pts[i]);
      if (!p.allFinite()) {
        ++dropped;
        continue;
      }
      s.points.push_back(p);
    }
    if (dropped) ctx_->error("segments seq " + std::to_string(m.seq) + ": " + std::to_string(dropped) + " non-finite points dropped");
    // The segmenter's "unknown" roll/pitch/z (its sigmas) -> the last known ones.
    if (m.z_sigma < 1.0 && std::isfinite(m.z)) last_z_ = m.z;
    if (m.roll_pitch_sigma < 0.5 && std::isfinite(m.roll) && std::isfinite(m.pitch)) last_rp_ = {m.roll, m.pitch};
    s.z = last_z_.value_or(0.0);
    s.roll = last_rp_ ? last_rp_->first : 0.0;
    s.pitch = last_rp_ ? last_rp_->second : 0.0;
    std::optional<double> dyaw;
    if (use_imu_) {
      if (have_prev_) dyaw = imu_.integral(prev_utime_, m.utime);
      imu_.drop_before(have_prev_ ? std::min(prev_utime_, m.utime) : m.utime);
    }
    const nd::Result r = loc_->process(s, dyaw);
    have_prev_ = true;
    prev_utime_ = m.utime;
    publish(m, r);
    if (r.status == nd::Status::kLost && last_status_ != nd::Status::kLost)
      ctx_->error("LOST at scan " + std::to_string(m.scan_seq) + ": " + r.text);
    last_status_ = r.status;
    ++scans_;
    ++counts_[std::min(2, int(r.status))];
    iterations_ += r.iterations;
    points_ += r.num_points;
    const double dt = thread_cpu_us() - t0;
    cpu_total_us_ += dt;
    cpu_us_.push_back(dt);
  }

  void publish(const fploc::segments_t& m, const nd::Result& r) {
    fploc::pose_t o{};
    o.utime = m.utime;
    o.seq = seq_++;
    o.status = int8_t(std::min(2, int(r.status)));
    o.keyframe = r.matched;
    o.final_estimate = true;
    o.floor_index = int16_t(floor_.index);
    o.floor = floor_.name;
    o.position[0] = r.x;
    o.position[1] = r.y;
    o.position[2] = r.z + floor_.elevation;  // absolute (pose_t convention)
    const Eigen::Quaterniond q = Eigen::AngleAxisd(r.yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(r.pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(r.roll, Eigen::Vector3d::UnitX());
    o.orientation[0] = q.x();
    o.orientation[1] = q.y();
    o.orientation[2] = q.z();
    o.orientation[3] = q.w();
    for (double& c : o.covariance) c = 0;
    const int ix[3] = {0, 1, 5};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) o.covariance[ix[i] * 6 + ix[j]] = r.covariance(i, j);
    const double zs = std::isfinite(m.z_sigma) ? m.z_sigma : 1e3, rps = std::isfinite(m.roll_pitch_sigma) ? m.roll_pitch_sigma : 1e3;
    o.covariance[2 * 6 + 2] = zs * zs;
    o.covariance[3 * 6 + 3] = o.covariance[4 * 6 + 4] = rps * rps;
    out_.publish(o);
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::config::FloorRef floor_;
  std::unique_ptr<nd::Localizer> loc_;
  fploc::matcher::ImuYaw imu_;
  bool use_imu_ = true, have_prev_ = false, done_ = false;
  int64_t prev_utime_ = 0, seq_ = 0, scans_ = 0, iterations_ = 0, points_ = 0;
  int64_t counts_[3] = {0, 0, 0};
  std::optional<double> last_z_;
  std::optional<std::pair<double, double>> last_rp_;
  nd::Status last_status_ = nd::Status::kNotInitialised;
  std::string stats_file_;
  fploc::rt::Publisher<fploc::pose_t> out_;
  double cpu_total_us_ = 0;
  std::vector<double> cpu_us_;
};

}  // namespace

FPLOC_REGISTER_NODE(NdtNode)
