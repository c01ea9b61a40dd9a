// fploc-amcl: the AMCL baseline (modules/amcl). FPLOC_FEATURES (as a planar scan) + odometry ->
// nav2-style AMCL on the floor plan -> FPLOC_AMCL_POSE (pose_t, every scan: the last estimate carried
// forward with the odometry, as nav2's map -> odom transform; 6-DoF with the segmenter's roll/pitch/z;
// covariance from the particles; status OK while their (x, y) 1-sigma spread is within 0.5 m, else POOR;
// keyframe = a filter update happened at this scan).
//
// Odometry (option `odometry`):
//  - "pose": pose_t on the `odom` port (fploc-odometry's FPLOC_ODOM_POSE): the LiDAR odometry a
//    wheel-less robot would give AMCL; only the motion between consecutive poses is used;
//  - "simulated-wheel": ground_truth_t on the `ground_truth` port (the simulator's FPLOC_GROUND_TRUTH)
//    turned into wheel odometry with scale error, yaw drift and noise (modules/amcl/odometry.h). The
//    filter only ever sees that odometry's increments, never the ground truth itself.
// Scans and odometry are paired by utime: the sample at the scan's start time, else the two around it
// interpolated (when at most Settings::odometry_max_gap_s apart). Everything depends on the
// messages only (seeded random numbers, no wall clock), so `fploc replay` stays byte-reproducible; the
// thread CPU time per scan goes to stderr and the optional stats file, never into a pose.
#include <fploc/features_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/pose_t.hpp>
#include <time.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <deque>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <vector>

#include "fploc/amcl/amcl.h"
#include "fploc/amcl/odometry.h"
#include "fploc/config/amcl.h"
#include "fploc/core/text_out.h"
#include "fploc/floorplan/io.h"
#include "fploc/adapters/features_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/config/floor_ref.h"
#include "fploc/runtime/node.h"

namespace {

using fploc::Pose2;
namespace am = fploc::amcl;

double thread_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e6 + double(ts.tv_nsec) * 1e-3;
}

class AmclNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"amcl", "amcl", "AMCL baseline (nav2's particle filter) on the floor plan, features as a planar scan",
            {fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::input<fploc::pose_t>("odom", "FPLOC_ODOM_POSE"),
             // Only with odometry: "simulated-wheel"; not connected unless the graph maps it.
             fploc::rt::input<fploc::ground_truth_t>("ground_truth", ""),
             // Re-initialisation as nav2's /initialpose (e.g. `fploc node initial-pose`); not connected by default.
             fploc::rt::input<fploc::pose_t>("initial_pose", ""),
             fploc::rt::output<fploc::pose_t>("pose", "FPLOC_AMCL_POSE"),
             // The odometry the filter used (in its odometry frame), e.g. to score the simulated wheel odometry.
             fploc::rt::output<fploc::pose_t>("odom_used", "")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::AmclOptions>();
    if (o.plan().file().empty()) throw std::runtime_error("amcl.plan.file: no floor plan given");
    const std::vector<std::string> layers(o.plan().layers().begin(), o.plan().layers().end());
    const fploc::FloorPlan plan = fploc::load_floor_plan(ctx.resolve_path(o.plan().file()), layers, o.plan().units(), o.plan().floor());
    floor_ = fploc::config::floor_ref(o.plan(), ctx.resolve_path(o.plan().file()));
    const am::Settings s = fploc::config::config_of(o);
    cfg_ = s.filter;
    amcl_ = std::make_unique<am::Amcl>(plan, cfg_);
    sxy_ = s.initial.std_xy_m;
    syaw_ = s.initial.std_yaw_deg * M_PI / 180.0;
    bins_ = s.scan.bins;
    range_min_ = s.scan.range_min_m;
    range_max_ = s.scan.range_max_m;
    guard_ = am::OdometryGuard(s.guard);
    max_gap_s_ = s.odometry_max_gap_s;
    stats_file_ = o.stats_file();
    wheel_mode_ = s.odometry == am::OdometrySource::kSimulatedWheel;
    if (wheel_mode_) {
      wheel_ = std::make_unique<am::WheelOdometrySim>(s.wheel);
      // The odometry frame starts at the initial pose when one is given (as fploc-odometry does), so its
      // trajectory can be scored against the ground truth; AMCL itself only uses increments.
      if (o.has_initial_pose() && !o.global_localization()) wheel_->set_start({o.initial_pose().x(), o.initial_pose().y(), o.initial_pose().yaw()});
      if (ctx.channel("ground_truth").empty())
        throw std::runtime_error("amcl.odometry = \"simulated-wheel\" needs the ground_truth port mapped (FPLOC_GROUND_TRUTH)");
    }
    if (!wheel_mode_ && ctx.channel("odom").empty())
      throw std::runtime_error("amcl.odometry = \"pose\" needs the odom port mapped");

    if (o.has_initial_pose() && !o.global_localization()) {
      const Pose2 p{o.initial_pose().x(), o.initial_pose().y(), o.initial_pose().yaw()};
      amcl_->init_pose(p, Eigen::Vector3d(sxy_ * sxy_, sxy_ * sxy_, syaw_ * syaw_).asDiagonal());
      std::cerr << "[" << ctx.name() << "] initial pose " << p.x << " " << p.y << " " << p.yaw << " (std " << sxy_
                << " m, " << syaw_ * 180 / M_PI << " deg), ";
    } else {
      amcl_->init_global();
      std::cerr << "[" << ctx.name() << "] no initial pose: global localization over " << amcl_->free_cells()
                << " free cells, ";
    }
    std::cerr << plan.elements.size() << " plan elements, odometry "
              << (wheel_mode_ ? "simulated-wheel (ground truth + errors)" : "pose (" + ctx.channel("odom") + ")") << "; particles "
              << cfg_.min_particles << ".." << cfg_.max_particles << ", alpha " << cfg_.alpha1 << "/" << cfg_.alpha2 << "/"
              << cfg_.alpha3 << "/" << cfg_.alpha4 << ", max_beams " << cfg_.max_beams << " of " << bins_ << ", recovery "
              << cfg_.recovery_alpha_slow << "/" << cfg_.recovery_alpha_fast << ", "
              << (cfg_.resampler == am::Resampler::kMultinomial ? "multinomial" : "low-variance") << ", "
              << (cfg_.estimate == am::EstimateMode::kBestCluster ? "best cluster" : "weighted mean") << ", seed " << cfg_.seed
              << "\n";

    out_ = ctx.advertise<fploc::pose_t>("pose");
    odom_out_ = ctx.advertise<fploc::pose_t>("odom_used");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) { on_features(m); });
    if (!wheel_mode_)
      ctx.subscribe<fploc::pose_t>("odom", [this](const fploc::pose_t& m) { on_odom(m.utime, fploc::adapters::pose2_of(m), m.seq); });
    else
      ctx.subscribe<fploc::ground_truth_t>("ground_truth", [this](const fploc::ground_truth_t& m) { on_truth(m); });
    ctx.subscribe<fploc::pose_t>("initial_pose", [this](const fploc::pose_t& m) { on_initial_pose(m); });
  }

  void shutdown() override {
    if (done_) return;
    done_ = true;
    for (const auto& f : frames_)
      ctx_->error("scan " + std::to_string(f.scan_seq) + ": no odometry at utime " + std::to_string(f.utime) + " before the end");
    const double mean_cpu = scans_ ? cpu_total_us_ / double(scans_) : 0.0;
    std::vector<double> c = cpu_us_;
    std::sort(c.begin(), c.end());
    auto pct = [&](double q) { return c.empty() ? 0.0 : c[std::min(c.size() - 1, size_t(q * double(c.size())))]; };
    std::cerr << "[" << ctx_->name() << "] " << scans_ << " scans, " << updates_ << " filter updates, " << resamples_
              << " resamplings, " << (updates_ ? double(particles_sum_) / double(updates_) : 0.0)
              << " particles per update, " << mean_cpu << " us thread CPU per scan (" << pct(0.5) << " p50, " << pct(0.99)
              << " p99); input problems: " << nonfinite_frames_ << " frames with non-finite features, " << empty_scans_
              << " scans without usable beams, " << unmatched_ << " scans without odometry, " << bad_odometry_
              << " non-finite odometry poses, " << guard_.jumps() << " odometry jumps, " << out_of_order_
              << " messages out of order\n";
    if (!stats_file_.empty()) {
      nlohmann::json j{{"node", ctx_->name()},
                       {"scans", scans_},
                       {"updates", updates_},
                       {"resamples", resamples_},
                       {"mean_particles_per_update", updates_ ? double(particles_sum_) / double(updates_) : 0.0},
                       {"mean_beams_per_update", updates_ ? double(beams_sum_) / double(updates_) : 0.0},
                       {"cpu_us_per_scan_mean", mean_cpu},
                       {"cpu_us_per_scan_p50", pct(0.5)},
                       {"cpu_us_per_scan_p99", pct(0.99)},
                       {"cpu_us_per_update_mean", updates_ ? cpu_update_us_ / double(updates_) : 0.0},
                       {"converged_fraction", scans_ ? double(converged_) / double(scans_) : 0.0},
                       {"ok_fraction", scans_ ? double(ok_) / double(scans_) : 0.0},
                       {"scans_without_odometry", unmatched_},
                       {"odometry_jumps", guard_.jumps()},
                       {"non_finite_odometry", bad_odometry_},
                       {"frames_with_non_finite_features", nonfinite_frames_},
                       {"scans_without_usable_beams", empty_scans_},
                       {"messages_out_of_order", out_of_order_},
                       {"odometry", wheel_mode_ ? "simulated-wheel" : "pose"}};
      std::ofstream f(stats_file_);
      if (f) f << fploc::json_text(j, 1) << "\n";
      else ctx_->error("stats_file '" + stats_file_ + "': cannot write");
    }
  }

 private:
  struct Frame {
    int64_t utime = 0, scan_seq = 0;
    double roll = 0, pitch = 0, z = 0, z_sigma = 0, rp_sigma = 0;
    std::vector<Eigen::Vector2d> points;
    double convert_cpu_us = 0;  // thread CPU of decoding the message
  };

  void on_features(const fploc::features_t& m) {
    const double t0 = thread_cpu_us();
    Frame f;
    int dropped = 0;
    try {
      const fploc::FeatureFrame ff = fploc::adapters::from_msg(m, &dropped);
      f.utime = ff.utime;
      f.scan_seq = ff.scan_seq;
      f.roll = ff.roll;
      f.pitch = ff.pitch;
      f.z = ff.z;
      f.z_sigma = ff.z_sigma;
      f.rp_sigma = ff.roll_pitch_sigma;
      f.points.reserve(ff.points.size());
      for (const auto& p : ff.points) f.points.push_back(p.p);
    } catch (const std::exception& e) {
      ctx_->error(std::string("features: ") + e.what());
      return;
    }
    if (dropped) {
      ++nonfinite_frames_;
      ctx_->error("features seq " + std::to_string(m.seq) + ": " + std::to_string(dropped) + " non-finite points dropped");
    }
    if (have_frame_ && f.utime <= last_frame_utime_) {
      ++out_of_order_;
      ctx_->error("features seq " + std::to_string(m.seq) + ": utime " + std::to_string(f.utime) + " not after the previous scan's (ignored)");
      return;
    }
    have_frame_ = true;
    last_frame_utime_ = f.utime;
    f.convert_cpu_us = thread_cpu_us() - t0;
    frames_.push_back(std::move(f));
    while (frames_.size() > kMaxPending) {
      ctx_->error("scan " + std::to_string(frames_.front().scan_seq) + ": no odometry with its utime on " +
                  ctx_->channel(wheel_mode_ ? "ground_truth" : "odom") + " (dropped)");
      ++unmatched_;
      frames_.pop_front();
    }
    match();
  }

  void on_truth(const fploc::ground_truth_t& m) {
    const Eigen::Quaterniond q(m.orientation[3], m.orientation[0], m.orientation[1], m.orientation[2]);
    if (!std::isfinite(m.position[0]) || !std::isfinite(m.position[1]) || !q.coeffs().allFinite() || q.squaredNorm() < 1e-12) {
      ++bad_odometry_;
      ctx_->error("ground_truth seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
      return;
    }
    fploc::StampedPose sp;
    sp.q = q.normalized();
    const Pose2 truth{m.position[0], m.position[1], sp.rpy()[2]};
    if (have_truth_ && m.utime <= last_truth_utime_) return;  // duplicate / out of order
    have_truth_ = true;
    last_truth_utime_ = m.utime;
    const Pose2 odo = wheel_->update(truth);
    if (odom_out_.valid() && !odom_out_.channel().empty())
      odom_out_.publish(fploc::adapters::make_pose_msg(m.utime, odom_seq_++, odo, 0, 0, m.position[2], Eigen::Matrix3d::Zero(), 0, 0, 0,
                                             false, true, -1, ""));  // the odometry frame: no floor
    on_odom(m.utime, odo, m.seq);
  }

  void on_odom(int64_t utime, const Pose2& p, int64_t seq) {
    if (have_odom_ && utime <= last_odom_utime_) {
      ++out_of_order_;
      ctx_->error("odometry seq " + std::to_string(seq) + ": utime " + std::to_string(utime) + " not after the previous (ignored)");
      return;
    }
    have_odom_ = true;
    last_odom_utime_ = utime;
    odoms_.emplace_back(utime, p);
    while (odoms_.size() > 4 * kMaxPending) odoms_.pop_front();
    match();
  }

  void on_initial_pose(const fploc::pose_t& m) {
    const Pose2 p = fploc::adapters::pose2_of(m);
    if (!am::finite(p)) {
      ctx_->error("initial_pose seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
      return;
    }
    // nav2 handleInitialPose: the message's covariance (x, y, yaw), or the option's spread when it has none.
    Eigen::Matrix3d cov;
    const int idx[3] = {0, 1, 5};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) cov(i, j) = m.covariance[idx[i] * 6 + idx[j]];
    if (!cov.allFinite() || !(cov(0, 0) > 0 && cov(1, 1) > 0 && cov(2, 2) > 0))
      cov = Eigen::Vector3d(sxy_ * sxy_, sxy_ * sxy_, syaw_ * syaw_).asDiagonal();
    amcl_->init_pose(p, cov);
    std::cerr << "[" << ctx_->name() << "] re-initialised at " << p.x << " " << p.y << " " << p.yaw << "\n";
  }

  // Pairs scans and odometry by utime, oldest first: the sample at a scan's utime, else the two samples around
  // it interpolated when at most odometry_max_gap_s apart (odometry at its own rate, e.g. a robot's 20-50 Hz
  // nav_msgs/Odometry imported from a bag); a scan with no such pair is dropped with one error naming it.
  void match() {
    while (!frames_.empty() && !odoms_.empty()) {
      const Frame& f = frames_.front();
      const int64_t tf = f.utime;
      while (!odoms_.empty() && odoms_.front().first < tf) {  // the newest sample before the scan is kept
        before_ = odoms_.front();
        odoms_.pop_front();
      }
      if (odoms_.empty()) return;  // wait for a sample at or after the scan
      const auto [to, po] = odoms_.front();
      if (to == tf) {
        process(f, po);
        before_ = odoms_.front();
        odoms_.pop_front();
      } else if (before_ && double(to - before_->first) * 1e-6 <= max_gap_s_) {
        process(f, fploc::interpolate(before_->second, po, double(tf - before_->first) / double(to - before_->first)));
      } else {
        ctx_->error("scan " + std::to_string(f.scan_seq) + ": no odometry at utime " + std::to_string(tf) +
                    (before_ ? " (samples at " + std::to_string(before_->first) + " and " + std::to_string(to) + ", more than " +
                                   fmt_s(max_gap_s_) + " s apart; dropped)"
                             : " (next odometry is " + std::to_string(to) + ", none before it; dropped)"));
        ++unmatched_;
      }
      frames_.pop_front();
    }
  }

  static std::string fmt_s(double s) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", s);
    return b;
  }

  void process(const Frame& f, const Pose2& raw_odom) {
    const double t0 = thread_cpu_us();
    Pose2 odom;
    std::string problem;
    if (!guard_.correct(raw_odom, &odom, &problem)) {
      ++bad_odometry_;
      ctx_->error("scan " + std::to_string(f.scan_seq) + ": " + problem);
      return;
    }
    if (!problem.empty()) ctx_->error("scan " + std::to_string(f.scan_seq) + ": " + problem);
    int skipped = 0;
    const am::LaserScan scan = am::points_to_scan(f.points, bins_, range_min_, range_max_, &skipped);
    const bool usable = std::any_of(scan.ranges.begin(), scan.ranges.end(), [](float r) { return std::isfinite(r); });
    if (!usable) {
      ++empty_scans_;
      ctx_->error("scan " + std::to_string(f.scan_seq) + " (" + std::to_string(f.points.size()) +
                  " features): no usable beam (empty, all non-finite or out of range): odometry only");
    }
    const am::StepInfo info = amcl_->process(odom, scan);
    if (!info.problem.empty() && usable)
      ctx_->error("scan " + std::to_string(f.scan_seq) + " (" + std::to_string(f.points.size()) + " features): " + info.problem);
    const Pose2 p = amcl_->pose_at(odom);
    const auto& st = amcl_->stats();
    Eigen::Matrix3d cov = st.cov;
    for (int i = 0; i < 3; ++i) cov(i, i) = std::max(cov(i, i), 0.0);
    if (!cov.allFinite()) cov = Eigen::Matrix3d::Identity() * 1e6;
    if (st.converged) ++converged_;
    // Status OK while the particles agree: 1-sigma of the (x, y) spread (largest eigenvalue) within
    // converged_dist (0.5 m). nav2's own flag (every particle within 0.5 m of the mean) is stricter than its
    // default motion noise ever lets the set be here; it is counted in the stats (converged_fraction).
    const double spread = std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov.topLeftCorner<2, 2>()).eigenvalues()[1]));
    const bool ok = spread <= cfg_.converged_dist;
    if (ok) ++ok_;
    out_.publish(fploc::adapters::make_pose_msg(f.utime, seq_++, p, f.roll, f.pitch, f.z + floor_.elevation, cov, f.z_sigma, f.rp_sigma, ok ? 0 : 1,
                                      info.updated, true, floor_.index, floor_.name));
    ++scans_;
    if (info.updated) {
      ++updates_;
      particles_sum_ += info.particles;
      beams_sum_ += info.beams_used;
    }
    if (info.resampled) ++resamples_;
    const double dt = thread_cpu_us() - t0 + f.convert_cpu_us;
    cpu_total_us_ += dt;
    if (info.updated) cpu_update_us_ += dt;
    cpu_us_.push_back(dt);
  }

  static constexpr size_t kMaxPending = 50;
  fploc::rt::Context* ctx_ = nullptr;
  fploc::config::FloorRef floor_;
  am::Config cfg_;
  std::unique_ptr<am::Amcl> amcl_;
  std::unique_ptr<am::WheelOdometrySim> wheel_;
  am::OdometryGuard guard_;
  bool wheel_mode_ = false;
  double sxy_ = 0.5, syaw_ = 0.26;
  int bins_ = 360;
  double range_min_ = 0, range_max_ = 100;
  std::string stats_file_;
  fploc::rt::Publisher<fploc::pose_t> out_, odom_out_;
  std::deque<Frame> frames_;
  std::deque<std::pair<int64_t, Pose2>> odoms_;
  std::optional<std::pair<int64_t, Pose2>> before_;  // the newest sample before the oldest pending scan
  double max_gap_s_ = 0.25;
  bool have_truth_ = false, done_ = false, have_odom_ = false, have_frame_ = false;
  int64_t last_truth_utime_ = 0, last_odom_utime_ = 0, last_frame_utime_ = 0, seq_ = 0, odom_seq_ = 0;
  int64_t scans_ = 0, updates_ = 0, resamples_ = 0, particles_sum_ = 0, beams_sum_ = 0, unmatched_ = 0, converged_ = 0;
  int64_t ok_ = 0, empty_scans_ = 0, bad_odometry_ = 0, out_of_order_ = 0, nonfinite_frames_ = 0;
  double cpu_total_us_ = 0, cpu_update_us_ = 0;
  std::vector<double> cpu_us_;
};

}  // namespace

FPLOC_REGISTER_NODE(AmclNode)
