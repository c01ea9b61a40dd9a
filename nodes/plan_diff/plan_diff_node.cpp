// fploc-plan-diff: plan-change detection as its own process. Each scan's wall features are placed on the
// plan with the localizer's estimate of that scan (pose_t with the same utime, FPLOC_POSE_LATEST in the
// shipped graphs) and fed to modules/plandiff; the flagged elements and the new structure found so far are
// published on FPLOC_PLAN_DIFF (plan_diff_t) at publish_hz of sensor time, so a composed replay is
// deterministic. With out_json / out_dxf set, the final diff is written at shutdown.
// Optional input `segments` (FPLOC_SEGMENTS; connected in graphs/realism*.pbtxt, unconnected by default): the
// segmenter's 3D wall points of the same scan (utime), which tell a new wall from furniture
// (plandiff::Options::new_min_height_m); without it new runs are not told by height. Only the scans it will use
// are read (frame_hz), and none with new_min_height_m 0.
#include <fploc/features_t.hpp>
#include <fploc/plan_diff_t.hpp>
#include <fploc/pose_t.hpp>
#include <fploc/segments_t.hpp>

#include <cmath>
#include <deque>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "fploc/adapters/features_t.h"
#include "fploc/adapters/plan_diff_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/config/plandiff.h"
#include "fploc/floorplan/io.h"
#include "fploc/plandiff/plan_diff.h"
#include "fploc/runtime/node.h"
#include "options/plandiff.pb.h"

namespace {


class PlanDiffNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"plan_diff", "plan_diff",
            "plan-change detection: missing / moved plan elements and new structure -> FPLOC_PLAN_DIFF",
            {fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::input<fploc::pose_t>("pose", "FPLOC_POSE_LATEST"),
             fploc::rt::input<fploc::segments_t>("segments", ""),
             fploc::rt::output<fploc::plan_diff_t>("diff", "FPLOC_PLAN_DIFF")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::PlanDiffOptions>();
    if (o.plan().file().empty()) throw std::runtime_error("plan_diff: plan.file is required");
    std::vector<std::string> layers(o.plan().layers().begin(), o.plan().layers().end());
    plan_ = fploc::load_floor_plan(ctx.resolve_path(o.plan().file()), layers, o.plan().units(), o.plan().floor());
    const fploc::config::PlanDiffSettings ps = fploc::config::config_of(o);
    diff_ = std::make_unique<fploc::plandiff::PlanDiff>(plan_, ps.diff);
    publish_us_ = int64_t(1e6 / ps.publish_hz);
    frame_us_ = ps.frame_hz > 0 ? int64_t(1e6 / ps.frame_hz) : 0;
    out_json_ = o.out_json();
    out_dxf_ = o.out_dxf();
    std::cerr << "[" << ctx.name() << "] " << plan_.elements.size() << " plan elements from " << plan_.source << "\n";
    out_ = ctx.advertise<fploc::plan_diff_t>("diff");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) {
      features_.push_back(fploc::adapters::from_msg(m));
      while (features_.size() > 30) features_.pop_front();
    });
    if (!ctx.channel("segments").empty() && ps.diff.new_min_height_m > 0)
      ctx.subscribe<fploc::segments_t>("segments", [this](const fploc::segments_t& m) {
        // A scan frame_hz leaves out (last_frame_ only grows) needs no heights.
        if (frame_us_ > 0 && last_frame_ != 0 && m.utime - last_frame_ < frame_us_) return;
        heights_.emplace_back(m.utime, fploc::adapters::heights_of(m));
        while (heights_.size() > 30) heights_.pop_front();
      });
    ctx.subscribe<fploc::pose_t>("pose", [this](const fploc::pose_t& m) { on_pose(m); });
  }

  void shutdown() override {
    if (!diff_ || done_) return;
    done_ = true;
    const auto r = diff_->result();
    if (!out_json_.empty()) {
      std::ofstream f(out_json_);
      fploc::plandiff::write_json(r, plan_, f);
      if (!f) ctx_->error("cannot write " + out_json_);
    }
    if (!out_dxf_.empty()) {
      std::ofstream f(out_dxf_);
      fploc::plandiff::write_dxf(r, plan_, f);
      if (!f) ctx_->error("cannot write " + out_dxf_);
    }
  }

 private:
  void on_pose(const fploc::pose_t& m) {
    if (m.status == 2) return;  // LOST: its features would draw a wrong diff
    const fploc::FeatureFrame* f = nullptr;
    for (const auto& x : features_)
      if (x.utime == m.utime) f = &x;
    if (!f || f->status != fploc::FeatureStatus::kOk) return;
    if (frame_us_ > 0 && last_frame_ != 0 && m.utime - last_frame_ < frame_us_) return;
    last_frame_ = m.utime;
    const fploc::Pose2 x = fploc::adapters::pose2_of(m);
    std::vector<Eigen::Vector2f> pts;
    pts.reserve(f->points.size());
    for (const auto& p : f->points) pts.emplace_back(float(p.p.x()), float(p.p.y()));
    const Eigen::Matrix3d cov = fploc::adapters::xy_yaw_covariance(m);
    const fploc::plandiff::PlanDiff::Heights* h = nullptr;
    for (const auto& [t, hh] : heights_)
      if (t == m.utime) h = &hh;
    diff_->add_frame(x.x, x.y, x.yaw, pts, &cov, m.status == 0, h);  // POOR: scale only, no change evidence
    if (last_publish_ == 0 || m.utime - last_publish_ >= publish_us_) {
      last_publish_ = m.utime;
      publish(m.utime);
    }
  }

  void publish(int64_t utime) { out_.publish(fploc::adapters::to_msg(diff_->result(), plan_, utime, seq_++)); }

  fploc::rt::Context* ctx_ = nullptr;
  fploc::FloorPlan plan_;
  std::unique_ptr<fploc::plandiff::PlanDiff> diff_;
  std::deque<fploc::FeatureFrame> features_;
  std::deque<std::pair<int64_t, fploc::plandiff::PlanDiff::Heights>> heights_;
  fploc::rt::Publisher<fploc::plan_diff_t> out_;
  int64_t publish_us_ = 1000000, frame_us_ = 0, last_publish_ = 0, last_frame_ = 0, seq_ = 0;
  std::string out_json_, out_dxf_;
  bool done_ = false;
};

}  // namespace

FPLOC_REGISTER_NODE(PlanDiffNode)
