// fploc-optimizer: FPLOC_FEATURES + FPLOC_FRAME_POSE (paired by scan_seq) -> windowed optimisation ->
// FPLOC_POSE (6-DoF, final estimates: poses that left the window or are max_final_delay_s old, every
// frame, in time order) and FPLOC_POSE_LATEST (the current window estimate of each frame, low latency):
// the WO step of fploc::localizer::Localizer. A building (.pbtxt/.ifc) loads every floor; the window follows the floor
// of the matcher's frames (frame_pose_t.floor_index): a new floor flushes the window (those poses are
// final on the old floor) and starts one on the new floor's plan. While the matcher is LOST, the frame's fit from the
// dead-reckoned pose goes out on `reseed` (FPLOC_RESEED: the matcher starts again there).
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/plan_diff_t.hpp>
#include <fploc/pose_t.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>

#include "fploc/adapters/features_t.h"
#include "fploc/adapters/frame_pose_t.h"
#include "fploc/adapters/plan_diff_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/config/localization.h"
#include "fploc/config/plan_source.h"
#include "fploc/floorplan/building.h"
#include "fploc/localizer/active_plan.h"
#include "fploc/localizer/localizer.h"
#include "fploc/matcher/plan_scale.h"
#include "fploc/runtime/node.h"

namespace {

using fploc::matcher::FitStatus;

class OptimizerNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"optimizer", "optimizer", "windowed keyframe optimisation (floor plan + velocity regularisation) -> 6-DoF pose",
            {fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::input<fploc::frame_pose_t>("frame_pose", "FPLOC_FRAME_POSE"),
             // Optional: the plan-change detector's verdicts (FPLOC_PLAN_DIFF), as the matcher's.
             fploc::rt::input<fploc::plan_diff_t>("plan_diff", ""),
             // Optional wheel odometry, as the matcher's `odom`: its increments predict the published
             // uncertainty's track (the innovation gate) between frames.
             fploc::rt::input<fploc::pose_t>("odom", ""),
             // Optional IMU (OS1_IMU): the gyro holds the yaw of the published status's dead reckoning
             // (localizer::UncertaintyConfig::dr_gyro_sigma_rad).
             fploc::rt::input<fploc::imu_t>("imu", ""),
             fploc::rt::output<fploc::pose_t>("pose", "FPLOC_POSE"),
             fploc::rt::output<fploc::pose_t>("latest", "FPLOC_POSE_LATEST"),
             // Optional: where the matcher should start again while it is LOST and the dead-reckoned pose's fit
             // explains the frame (localizer::UncertaintyConfig::dr_reseed_when_lost; FPLOC_RESEED in the shipped
             // graphs, the matcher's `reseed` input).
             fploc::rt::output<fploc::pose_t>("reseed", "")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::OptimizerOptions>();
    plan_ = fploc::localizer::ActivePlan(
        fploc::config::load_floor_maps(o.plan(), o.lookup(), [&](const std::string& p) { return ctx.resolve_path(p); },
                                       "optimizer.plan"),
        float(std::max(0.0, o.plan_diff_weight())), fploc::matcher::PlanCorrection(o.plan_diff_scale(), o.plan_diff_refine()),
        o.lookup());
    cfg_ = fploc::config::localizer_config(o);
    // Nobody to take a re-seed: none made (the window would restart on frames the matcher stays lost on).
    if (ctx.channel("reseed").empty()) cfg_.uncertainty.dr_reseed_when_lost = false;
    loc_ = plan_.make_localizer(cfg_);
    pose_out_ = ctx.advertise<fploc::pose_t>("pose");
    latest_out_ = ctx.advertise<fploc::pose_t>("latest");
    reseed_out_ = ctx.advertise<fploc::pose_t>("reseed");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) {
      try {
        features_[m.scan_seq] = fploc::adapters::from_msg(m);
      } catch (const std::exception& e) {
        ctx_->error(std::string("features: ") + e.what());
        return;
      }
      trim(features_);
      try_pair(m.scan_seq);
    });
    ctx.subscribe<fploc::plan_diff_t>("plan_diff", [this](const fploc::plan_diff_t& m) { on_plan_diff(m); });
    ctx.subscribe<fploc::pose_t>("odom", [this](const fploc::pose_t& m) {
      if (const auto p = fploc::adapters::finite_pose2_of(m)) loc_->add_odometry(m.utime, *p);
      else ctx_->error("odom seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
    });
    ctx.subscribe<fploc::imu_t>("imu", [this](const fploc::imu_t& m) { loc_->add_imu(m.utime, m.gyro[2]); });
    ctx.subscribe<fploc::frame_pose_t>("frame_pose", [this](const fploc::frame_pose_t& m) {
      frame_poses_[m.scan_seq] = m;
      trim(frame_poses_);
      try_pair(m.scan_seq);
    });
  }

  void shutdown() override {
    if (!loc_) return;
    std::vector<fploc::localizer::Pose> finals;
    loc_->flush(&finals);
    publish_finals(finals);
  }

 private:
  template <class M>
  static void trim(M& m) {
    while (m.size() > 64) m.erase(m.begin());
  }

  void try_pair(int64_t scan_seq) {
    auto f = features_.find(scan_seq);
    auto p = frame_poses_.find(scan_seq);
    if (f == features_.end() || p == frame_poses_.end()) return;
    if (f->second.utime != p->second.utime) {
      ctx_->error("scan_seq " + std::to_string(scan_seq) + ": features utime " + std::to_string(f->second.utime) +
                  " != frame_pose utime " + std::to_string(p->second.utime) + " (dropped)");
    } else if (scan_seq <= last_seq_ && have_last_) {
      ctx_->error("scan_seq " + std::to_string(scan_seq) + " arrived after " + std::to_string(last_seq_) + " (dropped)");
    } else if (p->second.status != int8_t(fploc::matcher::FitStatus::kNotInitialised)) {
      process(f->second, p->second);
      last_seq_ = scan_seq;
      have_last_ = true;
    }
    // Everything up to this scan is done (older unpaired entries will never pair).
    features_.erase(features_.begin(), std::next(f));
    frame_poses_.erase(frame_poses_.begin(), std::next(p));
  }

  void process(const fploc::FeatureFrame& f, const fploc::frame_pose_t& m) {
    if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.yaw)) {
      ctx_->error("frame_pose scan_seq " + std::to_string(m.scan_seq) + ": non-finite pose (dropped)");
      return;
    }
    // The matcher's z is absolute (its floor's elevation + the height above it; the segmenter's z carries
    // no floor), its sigma grown while a lift ride is integrated from the IMU.
    fploc::FeatureFrame fz = f;
    if (fploc::z_known(f)) {
      fz.z = m.z;
      if (std::isfinite(m.z_sigma) && m.z_sigma > fz.z_sigma && m.z_sigma < fploc::kZUnknownFromSigmaM) fz.z_sigma = m.z_sigma;
    }
    std::vector<fploc::localizer::Pose> finals;
    if (m.floor_index >= 0 && size_t(m.floor_index) < plan_.floors().maps.size() && m.floor_index != plan_.floor()) {
      // The matcher changed floor: the window's poses are final on the old floor (the arriving frame's z
      // first ends a lift ride's IMU-integrated z in them).
      loc_->end_z_stretch(fz);
      loc_->flush(&finals);
      publish_finals(finals);
      finals.clear();
      plan_.set_floor(m.floor_index);
      loc_ = plan_.make_localizer(cfg_);
      std::cerr << "[" << ctx_->name() << "] scan " << m.scan_seq << ": window on floor '" << m.floor << "'\n";
    }
    auto latest = loc_->optimize(fz, fploc::adapters::from_msg(m), &finals);
    // The floor of each frame is the matcher's (frame_pose_t); kept until the frame's pose is final.
    floor_of_[m.utime] = {m.floor_index, m.floor};
    if (latest) {
      plan_.add_scale_error(&*latest);
      latest_out_.publish(fploc::adapters::to_msg(*latest, latest_seq_++, m.floor_index, m.floor));
      // Status changes with their reason (pose_t has no text): e.g. POOR where the plan leaves a direction open,
      // said by the runtime (Context::status_changed) ...
      const std::string line = fploc::matcher::to_string(latest->status) + (latest->status_text.empty() ? "" : ": " + latest->status_text);
      const bool ok = latest->status == FitStatus::kOk;
      if (latest->status != last_status_) ctx_->status_changed("scan " + std::to_string(m.scan_seq) + ": " + line, !ok);
      // ... and the current reason in telemetry while not OK (the dashboard shows it beside the pose's status; the
      // reason may change while the status does not).
      if (!ok) ctx_->set_detail(line);
      last_status_ = latest->status;
    }
    if (const auto r = loc_->take_reseed()) {
      // The search radius as the 3 sigma the matcher reads from an initial pose's covariance.
      const double s = r->search_m / 3;
      char b[160];
      std::snprintf(b, sizeof b, "scan %lld (LOST): re-seeded at (%.2f, %.2f, %.1f deg) from the dead reckoning",
                    (long long)m.scan_seq, r->pose.x, r->pose.y, r->pose.yaw * 180 / M_PI);
      std::cerr << "[" << ctx_->name() << "] " << b << "\n";
      reseed_out_.publish(fploc::adapters::make_pose_msg(r->utime, reseed_seq_++, r->pose, fz.roll, fz.pitch, fz.z,
                                                         Eigen::Vector3d(s * s, s * s, 0.0).asDiagonal(), fz.z_sigma,
                                                         fz.roll_pitch_sigma, int8_t(FitStatus::kPoor), false, false,
                                                         m.floor_index, m.floor));
    }
    publish_finals(finals);
  }

  // As the matcher's: flagged elements get plan_diff_weight; when the plan correction changes, the
  // window's poses become final on the old plan and a new window starts on the corrected plan.
  void on_plan_diff(const fploc::plan_diff_t& m) {
    std::string error, said;
    const double scale_before = plan_.unexplained_scale_squared();  // what the window's poses were estimated with
    if (!plan_.apply_flags(fploc::adapters::flagged_elements(m), &error)) {
      ctx_->error("plan_diff seq " + std::to_string(m.seq) + ": optimizer.plan: " + error);
      return;
    }
    if (!plan_.correct(m.scale_error, m.scale_sigma, fploc::adapters::refined_offsets(m), m.utime, &said, &error)) {
      if (!error.empty()) ctx_->error(error);
      return;
    }
    std::vector<fploc::localizer::Pose> finals;
    loc_->flush(&finals);
    publish_finals(finals, scale_before);
    loc_ = plan_.make_localizer(cfg_);
    std::cerr << "[" << ctx_->name() << "] " << said << "\n";
  }

  // Each with the drawing scale's share of its uncertainty (ActivePlan::add_scale_error; s2 < 0: the current).
  void publish_finals(std::vector<fploc::localizer::Pose>& finals, double scale_s2 = -1) {
    for (auto& p : finals) {
      plan_.add_scale_error(&p, scale_s2 < 0 ? plan_.unexplained_scale_squared() : scale_s2);
      auto it = floor_of_.find(p.utime);
      const auto fl = it != floor_of_.end() ? it->second : std::pair<int, std::string>{-1, ""};
      pose_out_.publish(fploc::adapters::to_msg(p, pose_seq_++, fl.first, fl.second));
      if (it != floor_of_.end()) floor_of_.erase(floor_of_.begin(), std::next(it));
    }
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::localizer::ActivePlan plan_;  // before loc_: the Localizer reads its weights and map
  fploc::localizer::Config cfg_;
  std::unique_ptr<fploc::localizer::Localizer> loc_;
  fploc::rt::Publisher<fploc::pose_t> pose_out_, latest_out_, reseed_out_;
  std::map<int64_t, fploc::FeatureFrame> features_;
  std::map<int64_t, fploc::frame_pose_t> frame_poses_;
  std::map<int64_t, std::pair<int, std::string>> floor_of_;  // utime -> floor (index, name)
  int64_t last_seq_ = 0;
  bool have_last_ = false;
  int64_t pose_seq_ = 0, latest_seq_ = 0, reseed_seq_ = 0;
  FitStatus last_status_ = FitStatus::kOk;
};

}  // namespace

FPLOC_REGISTER_NODE(OptimizerNode)
