// fploc-odometry: the no-floor-plan baseline. FPLOC_FEATURES -> frame-to-local-map 2D ICP ->
// FPLOC_ODOM_POSE (6-DoF with the segmenter's roll/pitch/z, every frame, final_estimate = true), from
// the same initial pose as the matcher.
#include <fploc/features_t.hpp>
#include <fploc/pose_t.hpp>

#include <cmath>
#include <memory>

#include "fploc/adapters/features_t.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/config/localization.h"
#include "fploc/odometry/odometry.h"
#include "fploc/runtime/node.h"
#include "options/localization.pb.h"

namespace {

class OdometryNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"odometry", "odometry", "no-floor-plan baseline: frame-to-local-map 2D ICP on the features",
            {fploc::rt::input<fploc::features_t>("features", "FPLOC_FEATURES"),
             fploc::rt::output<fploc::pose_t>("pose", "FPLOC_ODOM_POSE")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<fploc::OdometryOptions>();
    odo_ = std::make_unique<fploc::odometry::Odometry2D>(fploc::config::config_of(o));
    odo_->set_pose({o.initial_pose().x(), o.initial_pose().y(), o.initial_pose().yaw()});
    out_ = ctx.advertise<fploc::pose_t>("pose");
    ctx.subscribe<fploc::features_t>("features", [this](const fploc::features_t& m) {
      fploc::FeatureFrame f;
      try {
        f = fploc::adapters::from_msg(m);
      } catch (const std::exception& e) {
        ctx_->error(std::string("features: ") + e.what());
        return;
      }
      const fploc::odometry::OdometryResult r = odo_->process(f);
      Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * (r.ok ? r.rms_m * r.rms_m : 1e6);
      out_.publish(fploc::adapters::make_pose_msg(f.utime, seq_++, r.pose, f.roll, f.pitch, f.z, cov, f.z_sigma,
                                        f.roll_pitch_sigma, r.ok ? 0 : 1, r.keyframe, true));
    });
  }

 private:
  fploc::rt::Context* ctx_ = nullptr;
  std::unique_ptr<fploc::odometry::Odometry2D> odo_;
  fploc::rt::Publisher<fploc::pose_t> out_;
  int64_t seq_ = 0;
};

}  // namespace

FPLOC_REGISTER_NODE(OdometryNode)
