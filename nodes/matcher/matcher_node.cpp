// fploc-matcher: FPLOC_FEATURES (+ OS1_IMU yaw rate) -> single-frame registration -> FPLOC_FRAME_POSE
// for every scan: the SFR step of fploc::localizer::Localizer. The map (plan or .fpmap) and the look-up
// come from the `matcher` options. A building (.pbtxt/.ifc) loads every floor; the FloorTracker (IMU
// accelerometer + the frames) decides the floor, the matcher switches to that floor's plan, searches the
// connection area there, and frame_pose_t carries the floor (the optimizer and relocalizer follow it).
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/plan_diff_t.hpp>
#include <fploc/pose_t.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "fploc/adapters/features_t.h"
#include "fploc/adapters/frame_pose_t.h"
#include "fploc/adapters/plan_diff_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/floorplan/building.h"
#include "fploc/localizer/active_plan.h"
#include "fploc/localizer/floor_tracker.h"
#include "fploc/config/localization.h"
#include "fploc/config/plan_source.h"
#include "fploc/localizer/localizer.h"
#include "fploc/matcher/plan_scale.h"
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
             // Optional: the optimizer's re-seeds while LOST (its `reseed` output, FPLOC_RESEED in the shipped graphs:
             // the frame registered from the dead-reckoned pose). Taken as an initial pose; a relocalizer's answer for
             // the same or an older frame is then stale (the robot's track, not a search around the last good pose).
             fploc::rt::input<fploc::pose_t>("reseed", ""),
             // The optimizer's window estimate of each frame (FPLOC_POSE_LATEST in the shipped graphs):
             // the next frame is predicted from it. Not connected by default: the matcher then predicts
             // from its own single-frame poses only, as the paper's SFR, and runs without an optimizer.
             fploc::rt::input<fploc::pose_t>("refined", ""),
             // Optional wheel odometry (pose_t in its own odometry frame, stamped with the scan times, e.g.
             // `fploc import-carmen`'s WHEEL_ODOM): the increment between two frames predicts the next one.
             fploc::rt::input<fploc::pose_t>("odom", ""),
             // Optional: the plan-change detector's verdicts (FPLOC_PLAN_DIFF); elements it marks missing or
             // moved get weight plan_diff_weight in the registration (default 0: left out); with plan_diff_scale
             // the plan is rescaled by its drawing-scale estimate once that is significant.
             fploc::rt::input<fploc::plan_diff_t>("plan_diff", ""),
             fploc::rt::output<fploc::frame_pose_t>("frame_pose", "FPLOC_FRAME_POSE")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::MatcherOptions>();
    plan_ = fploc::localizer::ActivePlan(
        fploc::config::load_floor_maps(o.plan(), o.lookup(), [&](const std::string& p) { return ctx.resolve_path(p); },
                                       "matcher.plan"),
        float(std::max(0.0, o.plan_diff_weight())), fploc::matcher::PlanCorrection(o.plan_diff_scale(), o.plan_diff_refine()),
        o.lookup());
    if (plan_.multi_floor())
      for (const auto& m : plan_.floors().maps) std::cerr << "[" << ctx.name() << "] " << m.note << "\n";
    if (plan_.multi_floor()) tracker_.emplace(plan_.floors().building, plan_.floor());
    cfg_ = fploc::config::localizer_config(o);
    loc_ = plan_.make_localizer(cfg_);
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
      // (A relocalizer's answer for a frame of the LOST stretch a re-seed ended: from 2 s before the re-seeded frame to
      // the newest frame registered when the re-seed was taken. An operator's pose stamped otherwise, e.g. 0, is taken.)
      if (m.utime >= reseed_utime_ - 2'000'000 && m.utime <= reseed_newest_) {
        std::cerr << "[" << ctx_->name() << "] initial_pose seq " << m.seq << " for a frame the optimizer re-seeded (ignored)\n";
        return;
      }
      on_initial_pose(m, "initial_pose");
    });
    ctx.subscribe<fploc::pose_t>("reseed", [this](const fploc::pose_t& m) {
      // Only while still LOST (the optimizer runs a frame or more behind: its re-seeds of the next LOST frames, or one
      // for a matcher a relocalizer's answer already brought back, would restart a track that holds), for a newer frame
      // than the last re-seed, and on this floor (a lift ride may have changed it since).
      if (last_status_ != FitStatus::kLost || m.utime <= reseed_utime_ || m.floor_index != plan_.floor()) return;
      if (on_initial_pose(m, "reseed")) {
        reseed_utime_ = m.utime;
        reseed_newest_ = std::max(m.utime, last_frame_utime_);
      }
    });
    ctx.subscribe<fploc::pose_t>("odom", [this](const fploc::pose_t& m) {
      if (const auto p = fploc::adapters::finite_pose2_of(m)) loc_->add_odometry(m.utime, *p);
      else ctx_->error("odom seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
    });
    ctx.subscribe<fploc::plan_diff_t>("plan_diff", [this](const fploc::plan_diff_t& m) { on_plan_diff(m); });
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
  // An initial pose (an operator's, the relocalizer's, the optimizer's re-seed) from `port`: false if not finite.
  bool on_initial_pose(const fploc::pose_t& m, const char* port) {
    const fploc::Pose2 p = fploc::adapters::pose2_of(m);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) {
      ctx_->error(std::string(port) + " seq " + std::to_string(m.seq) + ": non-finite pose (ignored)");
      return false;
    }
    // A pose on another floor (an operator's, a relocalization's): that floor's plan from now on.
    const int floors = int(plan_.floors().maps.size());
    if (m.floor_index >= 0 && m.floor_index < floors && m.floor_index != plan_.floor()) {
      const std::string from = plan_.floor_name();
      plan_.set_floor(m.floor_index);
      new_localizer();
      if (tracker_) tracker_->set_floor(plan_.floor(), "initial pose on floor '" + m.floor + "' (was '" + from + "')");
      std::cerr << "[" << ctx_->name() << "] initial pose on floor '" << m.floor << "' (was '" << from << "')\n";
    } else if (m.floor_index >= floors) {
      ctx_->error(std::string(port) + " seq " + std::to_string(m.seq) + ": floor_index " + std::to_string(m.floor_index) +
                  " but the plan has " + std::to_string(floors) + " floor(s) (floor kept)");
    }
    // Search within 3 sigma of the message's position covariance when it has one.
    const double var = std::max(m.covariance[0], m.covariance[7]);
    loc_->set_pose(p, std::isfinite(var) && var > 0 ? std::optional<double>(3 * std::sqrt(var)) : std::nullopt);
    return true;
  }

  void on_imu(const fploc::imu_t& m) {
    loc_->add_imu(m.utime, m.gyro[2]);
    if (tracker_) tracker_->add_imu(m.utime, {m.accel[0], m.accel[1], m.accel[2]});
    imu_.push_back({m.utime, m.gyro[2]});
    while (imu_.size() > 400) imu_.pop_front();
  }

  // The tracker's view of a registered frame; on a floor change: the new floor's Localizer, started at
  // the frame's pose with the connection area as its search region, registers the frame again.
  void track_floor(const fploc::FeatureFrame& f, fploc::localizer::FramePose* fp) {
    fploc::localizer::FloorObservation ob;
    ob.utime = f.utime;
    ob.pose = fp->match.pose;
    ob.pose_ok = fp->match.status == FitStatus::kOk;
    ob.inlier_ratio = fp->match.fit.inlier_ratio;
    ob.z = fp->z;
    ob.z_known = fploc::z_known(f);
    ob.z_sigma = f.z_sigma;
    ob.roll = f.roll, ob.pitch = f.pitch;
    ob.roll_pitch_known = fploc::roll_pitch_known(f);
    ob.attitude_t = std::isfinite(f.attitude_t) ? f.attitude_t : 0.0;
    const bool registered = fp->match.status != FitStatus::kNotInitialised;
    std::optional<fploc::localizer::FloorSwitch> sw;
    if (registered) sw = tracker_->update(ob);
    if (!sw && fp->match.status == FitStatus::kOk) last_ok_ = fp->match.pose, have_ok_ = true;
    // Where to start on the new floor: this frame's pose, or the last good one when the old floor's plan
    // no longer matched (after a lift ride the robot stands where it entered the cab).
    const fploc::Pose2 at = fp->match.status == FitStatus::kOk || !have_ok_ ? fp->match.pose : last_ok_;
    if (sw) {
      // A lift: the robot may have turned in the cab and the old plan no longer matched: search the lift's
      // area. Stairs/ramp: the pose was tracked all the way (one x/y frame), the area can be 25 m long.
      switch_floor(f, fp, *sw, at, sw->via.kind == fploc::ConnectionKind::kLift ? std::optional<double>(sw->search_radius_m)
                                                                                 : std::nullopt);
    } else if (!tracker_->probe_request().empty()) {
      // The plan no longer matches in a lift area: the same frame on each floor the lift serves (and on this
      // floor, the same search), from the last good pose within the lift's area.
      std::vector<fploc::localizer::FloorProbeResult> results;
      std::optional<fploc::Pose2> found;
      fploc::localizer::Config probe_cfg = cfg_;
      probe_cfg.matcher.element_weight = nullptr;
      for (const auto& q : tracker_->probe_request()) {
        fploc::localizer::Localizer probe(*plan_.floors().maps[size_t(q.floor)].lookup, probe_cfg);
        for (const auto& s : imu_) probe.add_imu(s.first, s.second);
        // From the last good pose, far enough to cover the lift's disc.
        probe.set_pose(at, q.search_radius_m + std::hypot(at.x - q.search_center.x(), at.y - q.search_center.y()));
        const auto r = probe.register_frame(f);
        results.push_back({q.floor, r.match.status == FitStatus::kOk, r.match.fit.inlier_ratio});
        std::cerr << "[" << ctx_->name() << "] scan " << f.scan_seq << ": plan of '" << q.name << "' in the lift area: "
                  << fploc::matcher::to_string(r.match.status) << ", " << int(std::lround(100 * r.match.fit.inlier_ratio)) << " %\n";
        if (q.floor != plan_.floor()) probe_pose_[q.floor] = r.match.pose;
      }
      sw = tracker_->probe_result(results);
      if (sw) switch_floor(f, fp, *sw, probe_pose_[sw->to], std::nullopt);
    }
    // Anything else the tracker noticed (a refused ride or probe, z from the building instead of the
    // segmenter, ...): printed and said on the frames of the next 3 s as a switch is.
    if (!sw && tracker_->status_text() != said_) {
      std::cerr << "[" << ctx_->name() << "] scan " << f.scan_seq << ": " << tracker_->status_text() << "\n";
      switch_text_ = tracker_->status_text();
      switch_until_ = f.utime + 3'000'000;
    }
    said_ = tracker_->status_text();
    fp->z = tracker_->pose_z();
    fp->z_sigma = tracker_->pose_z_sigma(fp->z_sigma);
  }

  // The new floor's Localizer, started at `at` (within `search_m` when given), registers the frame again.
  void switch_floor(const fploc::FeatureFrame& f, fploc::localizer::FramePose* fp, const fploc::localizer::FloorSwitch& sw,
                    const fploc::Pose2& at, std::optional<double> search_m) {
    plan_.set_floor(sw.to);
    std::cerr << "[" << ctx_->name() << "] scan " << f.scan_seq << ": " << tracker_->status_text() << "\n";
    new_localizer();
    if (search_m) loc_->set_pose(at, *search_m);
    else loc_->set_pose(at);
    *fp = loc_->register_frame(f);
    switch_text_ = tracker_->status_text();
    switch_until_ = f.utime + 3'000'000;
  }

  // A new Localizer on the plan in use (after a floor change or a plan correction), with the recent gyro.
  void new_localizer() {
    loc_ = plan_.make_localizer(cfg_);
    for (const auto& s : imu_) loc_->add_imu(s.first, s.second);
  }

  // plan_diff_weight: elements the diff flags get that weight. plan_diff_scale / plan_diff_refine: once
  // the correction changes (matcher/plan_scale.h), register against the corrected plan; the tracker
  // restarts there from its last pose moved into the new plan's frame (searching 0.1 m around it).
  void on_plan_diff(const fploc::plan_diff_t& m) {
    std::string error, said;
    if (!plan_.apply_flags(fploc::adapters::flagged_elements(m), &error)) {
      ctx_->error("plan_diff seq " + std::to_string(m.seq) + ": matcher.plan: " + error);
      return;
    }
    const double before = plan_.scale();
    if (!plan_.correct(m.scale_error, m.scale_sigma, fploc::adapters::refined_offsets(m), m.utime, &said, &error)) {
      if (!error.empty()) ctx_->error(error);
      return;
    }
    new_localizer();
    if (have_pose_)
      loc_->set_pose(fploc::matcher::rescaled_pose(last_pose_, 1 + before, 1 + plan_.scale(), fploc::matcher::scale_centre(plan_.plan())),
                     0.1);
    std::cerr << "[" << ctx_->name() << "] " << said << "\n";
    switch_text_ = said;
    switch_until_ = m.utime + 3'000'000;
  }

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
    fploc::localizer::FramePose fp = loc_->register_frame(f);
    last_frame_utime_ = f.utime;
    if (tracker_) track_floor(f, &fp);
    if (fp.match.status != FitStatus::kNotInitialised) last_pose_ = fp.match.pose, have_pose_ = true;
    fp.floor_index = plan_.floor();
    fp.floor = plan_.floor_name();
    const fploc::matcher::MatchResult& r = fp.match;
    // Wall-clock only outside replay (outputs must be reproducible there).
    const double solve_ms =
        ctx_->composed() ? 0.0 : std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
    if (r.status == fploc::matcher::FitStatus::kLost && last_status_ != fploc::matcher::FitStatus::kLost) ctx_->error("LOST at scan " + std::to_string(m.scan_seq) + ": " + r.text);
    last_status_ = r.status;
    fploc::frame_pose_t msg = fploc::adapters::to_msg(fp, seq_++, solve_ms);
    // A floor change is said on the frames of the next 3 s (never a silent switch).
    if (!switch_text_.empty() && m.utime <= switch_until_)
      msg.status_text += (msg.status_text.empty() ? "" : "; ") + switch_text_;
    out_.publish(msg);
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::localizer::ActivePlan plan_;  // before loc_: the Localizer reads its weights and map
  std::optional<fploc::localizer::FloorTracker> tracker_;
  fploc::localizer::Config cfg_;
  std::deque<std::pair<int64_t, double>> imu_;  // recent gyro z (a new floor's Localizer gets them)
  std::string switch_text_;
  std::string said_;  // the tracker's last status text
  int64_t switch_until_ = 0;
  fploc::Pose2 last_ok_;
  std::map<int, fploc::Pose2> probe_pose_;  // plan mismatch: where each floor's probe put the frame
  bool have_ok_ = false;
  fploc::Pose2 last_pose_;
  bool have_pose_ = false;
  std::unique_ptr<fploc::localizer::Localizer> loc_;
  fploc::rt::Publisher<fploc::frame_pose_t> out_;
  int64_t seq_ = 0;
  int64_t refined_ignored_ = 0;
  int64_t reseed_utime_ = INT64_MIN / 2;  // the newest frame the optimizer re-seeded (`reseed`)
  int64_t reseed_newest_ = INT64_MIN / 2;  // the newest frame registered when that re-seed was taken
  int64_t last_frame_utime_ = INT64_MIN / 2;  // the newest frame registered
  fploc::matcher::FitStatus last_status_ = fploc::matcher::FitStatus::kOk;
};

}  // namespace

FPLOC_REGISTER_NODE(MatcherNode)
