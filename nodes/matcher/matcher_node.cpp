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
#include <memory>
#include <optional>

#include "fploc/localizer/localizer.h"
#include "fploc/matcher/map.h"
#include "fploc/nodes/localization_convert.h"
#include "fploc/runtime/node.h"
#include "options/localization.pb.h"

namespace {

using fploc::FitStatus;

fploc::MatcherConfig config_of(const fploc::MatcherOptions& o) {
  fploc::MatcherConfig c;
  if (o.max_correspondence_m() > 0) c.gate_initial_m = o.max_correspondence_m();
  if (o.min_correspondence_m() > 0) c.gate_final_m = o.min_correspondence_m();
  if (o.huber_m() > 0) c.loss_scale_m = o.huber_m();
  if (!o.loss().empty()) c.loss = o.loss();
  if (o.max_iterations() > 0) c.max_iterations = o.max_iterations();
  if (o.max_rounds() > 0) c.max_outer = o.max_rounds();
  if (o.inlier_m() > 0) c.inlier_m = o.inlier_m();
  if (o.min_inlier_ratio() > 0) c.min_inlier_ratio = o.min_inlier_ratio();
  if (o.min_inliers() > 0) c.min_inliers = o.min_inliers();
  if (o.lost_after() > 0) c.lost_after = o.lost_after();
  if (o.max_jump_m() > 0) c.max_jump_m = o.max_jump_m();
  c.max_jump_rad = (o.max_jump_deg() > 0 ? o.max_jump_deg() : 30.0) * M_PI / 180;
  c.group_rule = !o.disable_group_rule();
  c.motion_model = !o.disable_motion_model();
  if (o.stride() > 0) c.stride = o.stride();
  if (o.max_points() != 0) c.max_points = o.max_points() < 0 ? 0 : o.max_points();
  c.deskew = !o.disable_deskew();
  if (o.prediction_sigma_m() != 0) c.prediction_sigma_m = std::max(0.0, o.prediction_sigma_m());
  if (o.prediction_sigma_deg() != 0) c.prediction_sigma_rad = std::max(0.0, o.prediction_sigma_deg()) * M_PI / 180;
  return c;
}

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
             fploc::rt::output<fploc::frame_pose_t>("frame_pose", "FPLOC_FRAME_POSE")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::MatcherOptions>();
    map_ = fploc::load_map(ctx, o.plan(), o.lookup(), "matcher");
    fploc::localizer::Config cfg;
    cfg.matcher = config_of(o);
    cfg.use_imu = !o.ignore_imu();
    if (o.initial_search_m() > 0) cfg.initial_search_m = o.initial_search_m();
    loc_ = std::make_unique<fploc::localizer::Localizer>(*map_.lookup, cfg);
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
      const fploc::Pose2 p = fploc::pose2_of(m);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) {
        ctx_->error("initial_pose seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
        return;
      }
      // Search within 3 sigma of the message's position covariance when it has one.
      const double var = std::max(m.covariance[0], m.covariance[7]);
      loc_->set_pose(p, std::isfinite(var) && var > 0 ? std::optional<double>(3 * std::sqrt(var)) : std::nullopt);
    });
    ctx.subscribe<fploc::pose_t>("refined", [this](const fploc::pose_t& m) {
      // Stale (a later frame was already registered) or LOST: not used; counted, said at shutdown.
      if (!loc_->refine(m.utime, fploc::pose2_of(m))) ++refined_ignored_;
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
      f = fploc::from_msg(m, &dropped);
    } catch (const std::exception& e) {
      ctx_->error(std::string("features: ") + e.what());
      return;
    }
    if (dropped) ctx_->error("features seq " + std::to_string(m.seq) + ": " + std::to_string(dropped) + " non-finite points dropped");
    const fploc::localizer::FramePose fp = loc_->register_frame(f);
    const fploc::MatchResult& r = fp.match;
    fploc::frame_pose_t o;
    o.utime = m.utime;
    o.seq = seq_++;
    o.scan_seq = m.scan_seq;
    o.status = int8_t(r.status);
    o.status_text = r.status == FitStatus::kOk ? "" : std::string(fploc::to_string(r.status)) + ": " + r.text;
    o.x = r.pose.x;
    o.y = r.pose.y;
    o.yaw = r.pose.yaw;
    for (int i = 0; i < 9; ++i) o.covariance[i] = r.covariance(i / 3, i % 3);
    o.roll = fp.roll;
    o.pitch = fp.pitch;
    o.z = fp.z;
    o.twist[0] = r.twist.vx;
    o.twist[1] = r.twist.vy;
    o.twist[2] = r.twist.w;
    o.num_points = r.fit.num_points;
    o.num_inliers = r.fit.num_inliers;
    o.inlier_ratio = r.fit.inlier_ratio;
    o.rms_residual_m = r.fit.rms_m;
    o.iterations = r.iterations;
    // Wall-clock only outside replay (outputs must be reproducible there).
    o.solve_ms = ctx_->composed() ? 0.0
                                  : std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
    if (r.status == FitStatus::kLost && last_status_ != FitStatus::kLost) ctx_->error("LOST at scan " + std::to_string(m.scan_seq) + ": " + r.text);
    last_status_ = r.status;
    out_.publish(o);
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::LocalizationMap map_;
  std::unique_ptr<fploc::localizer::Localizer> loc_;
  fploc::rt::Publisher<fploc::frame_pose_t> out_;
  int64_t seq_ = 0;
  int64_t refined_ignored_ = 0;
  FitStatus last_status_ = FitStatus::kOk;
};

}  // namespace

FPLOC_REGISTER_NODE(MatcherNode)
