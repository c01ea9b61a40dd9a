// fploc-relocalizer: global (re)localization as its own process. It watches the matcher's frame poses;
// while the matcher has no pose (NOT_INITIALISED) or is LOST, it searches the features of that scan over
// the plan — when LOST around the last good pose (or the pose the matcher holds) first, the whole plan
// once the loss lasts longer than `global_after_s` or when there never was a pose — and publishes an
// unambiguous answer on
// FPLOC_INITIAL_POSE, from which the matcher re-initialises (a restarted matcher waits for exactly that:
// NOT_INITIALISED right after a good pose means a local search). A tracking matcher is never touched.
// Time is the sensor's (message utimes), so composed replays stay deterministic.
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/pose_t.hpp>

#include <cmath>
#include <deque>
#include <iostream>
#include <memory>

#include "fploc/matcher/map.h"
#include "fploc/adapters/features_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/config/plan_source.h"
#include "fploc/config/relocalization.h"
#include "fploc/relocalization/relocalizer.h"
#include "fploc/runtime/node.h"
#include "options/relocalization.pb.h"

namespace {

using fploc::matcher::FitStatus;

class RelocalizerNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"relocalizer", "relocalizer",
            "global (re)localization while the matcher is lost or has no pose -> FPLOC_INITIAL_POSE",
            {fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::input<fploc::frame_pose_t>("frame_pose", "FPLOC_FRAME_POSE"),
             fploc::rt::output<fploc::pose_t>("initial_pose", "FPLOC_INITIAL_POSE")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::RelocalizerOptions>();
    map_ = fploc::config::load_map(o.plan(), o.lookup(), [&](const std::string& p) { return ctx.resolve_path(p); }, "relocalizer.plan");
    reloc_ = std::make_unique<fploc::reloc::Relocalizer>(*map_.plan, *map_.lookup, fploc::config::config_of(o));
    const fploc::reloc::Schedule when = fploc::config::schedule_of(o);
    radius_ = when.region_radius_m;
    global_after_us_ = int64_t(when.global_after_s * 1e6);
    interval_us_ = int64_t(when.min_interval_s * 1e6);
    std::cerr << "[" << ctx.name() << "] " << map_.plan->elements.size() << " elements, "
              << reloc_->free_cells() << " free search cells\n";
    out_ = ctx.advertise<fploc::pose_t>("initial_pose");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) {
      features_.push_back(m);
      while (features_.size() > 8) features_.pop_front();
    });
    ctx.subscribe<fploc::frame_pose_t>("frame_pose", [this](const fploc::frame_pose_t& m) { on_frame_pose(m); });
  }

 private:
  void on_frame_pose(const fploc::frame_pose_t& m) {
    const auto st = fploc::matcher::FitStatus(m.status);
    if (st == fploc::matcher::FitStatus::kOk) {
      last_ok_ = fploc::Pose2{m.x, m.y, m.yaw};
      last_ok_utime_ = m.utime;
      have_ok_ = true;
      lost_since_ = 0;
      return;
    }
    if (st != fploc::matcher::FitStatus::kLost && st != fploc::matcher::FitStatus::kNotInitialised) return;  // POOR: the matcher copes
    if (lost_since_ == 0) lost_since_ = m.utime;
    if (last_search_ != 0 && m.utime - last_search_ < interval_us_) return;
    const fploc::features_t* f = nullptr;
    for (const auto& x : features_)
      if (x.scan_seq == m.scan_seq) f = &x;
    if (!f) return;
    last_search_ = m.utime;
    fploc::FeatureFrame frame;
    try {
      frame = fploc::adapters::from_msg(*f);
    } catch (const std::exception& e) {
      ctx_->error(std::string("features: ") + e.what());
      return;
    }
    // LOST: first around the last good pose (or, if there never was one, around the pose the matcher
    // holds — the given initial pose); the whole plan once the loss lasts longer than global_after_s.
    // NOT_INITIALISED right after a good pose (the matcher was restarted): around that pose too.
    std::optional<fploc::reloc::SearchRegion> region;
    const bool local = m.utime - lost_since_ < global_after_us_ &&
                       (st == fploc::matcher::FitStatus::kLost || (have_ok_ && m.utime - last_ok_utime_ < global_after_us_));
    if (local) region = fploc::reloc::SearchRegion{have_ok_ ? last_ok_ : fploc::Pose2{m.x, m.y, m.yaw}, radius_, M_PI};
    const fploc::reloc::RelocResult r = reloc_->locate(frame, region);
    const std::string where = local ? "near the last pose" : "over the whole plan";
    if (r.status != fploc::reloc::RelocStatus::kFound) {
      const std::string text = std::string(fploc::reloc::to_string(r.status)) + " " + where + ": " + r.text;
      if (text != last_text_) ctx_->error("scan " + std::to_string(m.scan_seq) + ": " + text);
      last_text_ = text;
      return;
    }
    last_text_.clear();
    std::cerr << "[" << ctx_->name() << "] scan " << m.scan_seq << " (" << to_string(st) << "): " << r.text
              << " " << where << "\n";
    out_.publish(fploc::adapters::make_pose_msg(f->utime, seq_++, r.pose, f->roll, f->pitch, f->z,
                                      Eigen::Matrix3d::Identity() * r.fit.rms_m * r.fit.rms_m, f->z_sigma,
                                      f->roll_pitch_sigma, 0, false, true));
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::matcher::LocalizationMap map_;
  std::unique_ptr<fploc::reloc::Relocalizer> reloc_;
  fploc::rt::Publisher<fploc::pose_t> out_;
  std::deque<fploc::features_t> features_;
  fploc::Pose2 last_ok_;
  bool have_ok_ = false;
  int64_t lost_since_ = 0, last_search_ = 0, last_ok_utime_ = 0, seq_ = 0;
  double radius_ = 3.0;
  int64_t global_after_us_ = 2000000, interval_us_ = 500000;
  std::string last_text_;
};

}  // namespace

FPLOC_REGISTER_NODE(RelocalizerNode)
