// fploc-laser2d: the 2D LiDAR mode's front end. laser_scan_t (LASER_SCAN) -> LOAM corner/surface features of
// the planar scan (modules/laser2d) -> features_t (FPLOC_FEATURES), the message the matcher, optimizer,
// odometry and AMCL consume from the 3D pipeline. Roll/pitch: from the IMU's accelerometer (gravity, averaged
// since the previous scan) when the `imu` port is connected and samples arrive, else zero (a level robot);
// z is fixed (option z_m).
#include <fploc/features_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/laser_scan_t.hpp>

#include <cmath>

#include "fploc/laser2d/laser2d.h"
#include "fploc/adapters/features_t.h"
#include "fploc/config/laser2d.h"
#include "fploc/runtime/node.h"
#include "options/laser2d.pb.h"

namespace {

namespace l2 = fploc::laser2d;

class Laser2dNode : public fploc::rt::Node {
 public:
  static fploc::rt::NodeSpec spec() {
    return {"laser2d", "laser2d", "2D LiDAR scans -> LOAM corner/surface features (features_t) for the 2D mode",
            {fploc::rt::input<fploc::laser_scan_t>("scan", "LASER_SCAN"),
             fploc::rt::input<fploc::imu_t>("imu", ""),  // optional: roll/pitch from gravity
             fploc::rt::output<fploc::features_t>("features", "FPLOC_FEATURES")}};
  }

  void setup(fploc::rt::Context& ctx) override {
    ctx_ = &ctx;
    l2_ = std::make_unique<l2::Laser2dFeatures>(fploc::config::config_of(ctx.options<fploc::Laser2dOptions>()));
    out_ = ctx.advertise<fploc::features_t>("features");
    ctx.subscribe<fploc::laser_scan_t>("scan", [this](const fploc::laser_scan_t& m) { on_scan(m); });
    ctx.subscribe<fploc::imu_t>("imu", [this](const fploc::imu_t& m) { on_imu(m); });
  }

 private:
  void on_imu(const fploc::imu_t& m) {
    const Eigen::Vector3d a(m.accel[0], m.accel[1], m.accel[2]);
    if (!a.allFinite() || a.norm() < 5 || a.norm() > 15) return;  // not gravity-dominated: skip
    accel_sum_ += a;
    ++accel_n_;
  }

  void on_scan(const fploc::laser_scan_t& m) {
    l2::PlanarScan s;
    s.utime = m.utime;
    s.seq = seq_;
    s.angle_min = m.angle_min;
    s.angle_increment = m.angle_increment;
    s.time_increment = m.time_increment;
    s.range_min = m.range_min;
    s.range_max = m.range_max;
    s.ranges.assign(m.ranges.begin(), m.ranges.end());
    if (accel_n_ > 0) {
      // Specific force points up in a level sensor: roll = atan2(ay, az), pitch = atan2(-ax, |(ay, az)|).
      const Eigen::Vector3d g = accel_sum_ / double(accel_n_);
      roll_ = std::atan2(g.y(), g.z());
      pitch_ = std::atan2(-g.x(), std::hypot(g.y(), g.z()));
      rp_sigma_ = 0.01;
      accel_sum_.setZero();
      accel_n_ = 0;
    }
    const auto& f = l2_->process(s, roll_, pitch_, rp_sigma_);
    if (f.status == fploc::FeatureStatus::kBadInput && !m.ranges.empty())
      ctx_->error("scan utime " + std::to_string(m.utime) + ": bad geometry (angle_increment " +
                  std::to_string(m.angle_increment) + ")");
    fploc::features_t msg;
    fploc::adapters::to_msg(f, seq_, msg);
    ++seq_;
    out_.publish(msg);
  }

  fploc::rt::Context* ctx_ = nullptr;
  std::unique_ptr<l2::Laser2dFeatures> l2_;
  fploc::rt::Publisher<fploc::features_t> out_;
  Eigen::Vector3d accel_sum_ = Eigen::Vector3d::Zero();
  int accel_n_ = 0;
  double roll_ = 0, pitch_ = 0, rp_sigma_ = 0.01;
  int64_t seq_ = 0;
};

}  // namespace
FPLOC_REGISTER_NODE(Laser2dNode)
