// fploc-relocalizer: global (re)localization as its own process. It watches the matcher's frame poses;
// while the matcher has no pose (NOT_INITIALISED) or is LOST, it searches the features of that scan over
// the plan — when LOST around the last good pose (or the pose the matcher holds) first, the whole plan
// once the loss lasts longer than `global_after_s` or when there never was a pose — and publishes an
// unambiguous answer on
// FPLOC_INITIAL_POSE, from which the matcher re-initialises (a restarted matcher waits for exactly that:
// NOT_INITIALISED right after a good pose means a local search). A tracking matcher is never touched.
// Time is the sensor's (message utimes), so composed replays stay deterministic.
// A building (.pbtxt/.ifc): every floor is loaded; the search runs on the floor of the matcher's frame
// (frame_pose_t.floor_index), and right after the matcher changed floor (within global_after_s) the
// local search region is the connection area between the two floors (the disc holding its polygon).
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
#include "fploc/floorplan/building.h"
#include "fploc/localizer/floor_maps.h"
#include "fploc/localizer/floor_tracker.h"
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
    floors_ = fploc::config::load_floor_maps(o.plan(), o.lookup(), [&](const std::string& p) { return ctx.resolve_path(p); },
                                             "relocalizer.plan");
    floor_ = floors_.initial;
    for (const auto& m : floors_.maps)
      relocs_.push_back(std::make_unique<fploc::reloc::Relocalizer>(*m.plan, *m.lookup, fploc::config::config_of(o)));
    when_ = fploc::config::schedule_of(o);
    global_after_us_ = int64_t(when_.global_after_s * 1e6);
    interval_us_ = int64_t(when_.min_interval_s * 1e6);
    for (size_t i = 0; i < relocs_.size(); ++i)
      std::cerr << "[" << ctx.name() << "] floor '" << floors_.building->floors[i].name << "': "
                << floors_.maps[i].plan->elements.size() << " elements, " << relocs_[i]->free_cells() << " free search cells\n";
    out_ = ctx.advertise<fploc::pose_t>("initial_pose");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) {
      features_.push_back(m);
      while (features_.size() > 8) features_.pop_front();
    });
    ctx.subscribe<fploc::frame_pose_t>("frame_pose", [this](const fploc::frame_pose_t& m) { on_frame_pose(m); });
  }

 private:
  // The connection between the floor left and the current one whose area (with 1 m around it) holds p.
  const fploc::FloorConnection* connection_near(const fploc::Pose2& p) const {
    const auto& b = *floors_.building;
    const std::string& a = b.floors[size_t(floor_from_)].name;
    const std::string& n = b.floors[size_t(floor_)].name;
    const fploc::FloorConnection* best = nullptr;
    double best_d = 1.0;
    for (const auto& c : b.connections) {
      if (!((c.from_floor == a && c.to_floor == n) || (c.from_floor == n && c.to_floor == a))) continue;
      Eigen::Vector2d ctr;
      double rad = 0;
      fploc::localizer::FloorTracker::search_disc(c.polygon, 0, &ctr, &rad);
      const double d = c.contains({p.x, p.y}) ? 0.0 : std::max(0.0, (Eigen::Vector2d(p.x, p.y) - ctr).norm() - rad);
      if (d <= best_d) best = &c, best_d = d;
    }
    return best;
  }

  void on_frame_pose(const fploc::frame_pose_t& m) {
    const auto st = fploc::matcher::FitStatus(m.status);
    if (m.floor_index >= 0 && size_t(m.floor_index) < relocs_.size() && m.floor_index != floor_) {
      floor_from_ = floor_;
      floor_ = m.floor_index;
      floor_changed_ = m.utime;
    }
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
    // (No farther from the last good pose than the platform can have driven since: on corridor s2 mixed the answer
    // lay 2.8 m from the last good fix, 0.5 s after it.)
    const double radius = have_ok_ ? fploc::reloc::local_radius_m(when_, (m.utime - last_ok_utime_) * 1e-6) : when_.region_radius_m;
    if (local) region = fploc::reloc::SearchRegion{have_ok_ ? last_ok_ : fploc::Pose2{m.x, m.y, m.yaw}, radius, M_PI};
    std::string where = local ? "near the last pose" : "over the whole plan";
    // Just after a floor change: the connection area between the two floors.
    if (floor_changed_ != 0 && m.utime - floor_changed_ < global_after_us_)
      if (const fploc::FloorConnection* c = connection_near(have_ok_ ? last_ok_ : fploc::Pose2{m.x, m.y, m.yaw})) {
        Eigen::Vector2d ctr;
        double rad = 0;
        fploc::localizer::FloorTracker::search_disc(c->polygon, 1.0, &ctr, &rad);
        region = fploc::reloc::SearchRegion{fploc::Pose2{ctr.x(), ctr.y(), 0}, rad, M_PI};
        where = "in the " + std::string(fploc::to_string(c->kind)) + " area '" + c->name + "' of floor '" + m.floor + "'";
      }
    if (floors_.multi_floor() && where.find("floor '") == std::string::npos) where += " of floor '" + m.floor + "'";
    const fploc::reloc::RelocResult r = relocs_[size_t(floor_)]->locate(frame, region);
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
                                      f->roll_pitch_sigma, 0, false, true, m.floor_index, m.floor));
  }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::localizer::FloorMaps floors_;
  std::vector<std::unique_ptr<fploc::reloc::Relocalizer>> relocs_;  // one per floor
  int floor_ = 0, floor_from_ = 0;
  int64_t floor_changed_ = 0;
  fploc::rt::Publisher<fploc::pose_t> out_;
  std::deque<fploc::features_t> features_;
  fploc::Pose2 last_ok_;
  bool have_ok_ = false;
  int64_t lost_since_ = 0, last_search_ = 0, last_ok_utime_ = 0, seq_ = 0;
  fploc::reloc::Schedule when_;
  int64_t global_after_us_ = 2000000, interval_us_ = 500000;
  std::string last_text_;
};

}  // namespace

FPLOC_REGISTER_NODE(RelocalizerNode)
