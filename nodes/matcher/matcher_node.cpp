// fploc-matcher: FPLOC_FEATURES (+ OS1_IMU yaw rate) -> single-frame registration -> FPLOC_FRAME_POSE
// for every scan: the SFR step of fploc::localizer::Localizer. The map (plan or .fpmap) and the look-up
// come from the `matcher` options.
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/pose_t.hpp>

#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "fploc/adapters/features_t.h"
#include "fploc/adapters/frame_pose_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/config/localization.h"
#include "fploc/config/plan_source.h"
#include "fploc/localizer/localizer.h"
#include "fploc/runtime/node.h"

namespace {

using fploc::matcher::FitStatus;

class MatcherNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"matcher", "matcher", "single-frame (x, y, yaw) registration of 2D features against the floor plan",
            {fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::input<fploc::imu_t>("imu", "OS1_IMU"),
             fploc::rt::input<fploc::pose_t>("initial_pose", "FPLOC_INITIAL_POSE"),
             // The optimizer's window estimate of each frame (FPLOC_POSE_LATEST in the shipped graphs):
             // the next frame is predicted from it. Not connected by default: the matcher then predicts
             // from its own single-frame poses only, as the paper's SFR, and runs without an optimizer.
             fploc::rt::input<fploc::pose_t>("refined", ""),
             // Optional wheel odometry (pose_t in its own odometry frame, stamped with the scan times, e.g.
             // `fploc import-carmen`'s WHEEL_ODOM): the increment between two frames predicts the next one.
             fploc::rt::input<fploc::pose_t>("odom", ""),
             fploc::rt::output<fploc::frame_pose_t>("frame_pose", "FPLOC_FRAME_POSE")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::MatcherOptions>();
    map_ = fploc::config::load_map(o.plan(), o.lookup(), [&](const std::string& p) { return ctx.resolve_path(p); },
                                   "matcher.plan");
    loc_ = std::make_unique<fploc::localizer::Localizer>(*map_.lookup, fploc::config::localizer_config(o));
    // The graph's initial pose is where the run starts; a restarted matcher (crash, module swap) waits for
    // a pose instead (FPLOC_INITIAL_POSE: the relocalizer searches around the last good pose).
    if (!o.wait_for_initial_pose() && ctx.restarts() == 0)
      loc_->set_pose({o.initial_pose().x(), o.initial_pose().y(), o.initial_pose().yaw()});
    else if (ctx.restarts() > 0)
      std::cerr << "[" << ctx.name() << "] restart " << ctx.restarts() << ": waiting for a pose on initial_pose\n";
    out_ = ctx.advertise<fploc::frame_pose_t>("frame_pose");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) { on_features(m); });
    ctx.subscribe<fploc::imu_t>("imu", [this](const fploc::imu_t& m) { on_imu(m); });
    ctx.subscribe<fploc::pose_t>("initial_pose", [this](const fploc::pose_t& m) {
      const fploc::Pose2 p = fploc::adapters::pose2_of(m);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) {
        ctx_->error("initial_pose seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
        return;
      }
      // Search within 3 sigma of the message's position covariance when it has one.
      const double var = std::max(m.covariance[0], m.covariance[7]);
      loc_->set_pose(p, std::isfinite(var) && var > 0 ? std::optional<double>(3 * std::sqrt(var)) : std::nullopt);
    });
    ctx.subscribe<fploc::pose_t>("odom", [this](const fploc::pose_t& m) {
      const fploc::Pose2 p = fploc::adapters::pose2_of(m);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) {
        ctx_->error("odom seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
        return;
      }
      loc_->add_odometry(m.utime, p);
    });
    ctx.subscribe<fploc::pose_t>("refined", [this](const fploc::pose_t& m) {
      // Stale (a later frame was already registered) or LOST: not used; counted, said at shutdown.
      if (!loc_->refine(m.utime, fploc::adapters::pose2_of(m))) ++refined_ignored_;
    });
  }

  void shutdown() override {
    if (refined_ignored_ > 0)
      std::cerr << "[" << ctx_->name() << "] " << refined_ignored_
                << " refined poses not used (for an older frame, or while LOST)\n";
  }

 private:
  void on_imu(const fploc::imu_t& m) { loc_->add_imu(m.utime, m.gyro[2]); }

  void on_features(const fploc::features_t& m) {
    const auto t_start = std::chrono::steady_clock::now();
    fploc::FeatureFrame f;
    int dropped = 0;
    try {
      f = fploc::adapters::from_msg(m, &dropped);
    } catch (const std::exception& e) {
      ctx_->error(std::string("features: ") + e.what());
      return;
    }
    if (dropped) ctx_->error("features seq " + std::to_string(m.seq) + ": " + std::to_string(dropped) + " non-finite points dropped");
    const fploc::localizer::FramePose fp = loc_->register_frame(f);
    const fploc::matcher::MatchResult& r = fp.match;
    // Wall-clock only outside replay (outputs must be reproducible there).
    const double solve_ms =
        ctx_->composed() ? 0.0 : std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
    if (r.status == fploc::matcher::FitStatus::kLost && last_status_ != fploc::matcher::FitStatus::kLost) ctx_->error("LOST at scan " + std::to_string(m.scan_seq) + ": " + r.text);
    last_status_ = r.status;
    out_.publish(fploc::adapters::to_msg(fp, seq_++, solve_ms));
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::matcher::LocalizationMap map_;
  std::unique_ptr<fploc::localizer::Localizer> loc_;
  fploc::rt::Publisher<fploc::frame_pose_t> out_;
  int64_t seq_ = 0;
  int64_t refined_ignored_ = 0;
  fploc::matcher::FitStatus last_status_ = fploc::matcher::FitStatus::kOk;
};

}  // namespace

FPLOC_REGISTER_NODE(MatcherNode)
