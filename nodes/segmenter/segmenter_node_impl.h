// The segmenter node body shared by fploc-segmenter (paper) and fploc-segmenter-ransac (PCL): same ports,
// same message, same options field `segmenter`, so a graph swaps the executable only.
#pragma once
#include <fploc/imu_t.hpp>
#include <fploc/pose_t.hpp>
#include <fploc/scan_t.hpp>
#include <fploc/segments_t.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "fploc/core/scan.h"
#include "fploc/adapters/pose_t.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/adapters/segments_t.h"
#include "fploc/config/perception.h"
#include "fploc/floorplan/building.h"
#include "fploc/runtime/node.h"
#include "fploc/segmentation/scan_imu_sync.h"

namespace fploc {

template <class Traits>
class SegmenterNodeT : public rt::Node {
 public:
  static rt::NodeSpec spec() {
    return {Traits::kType, "segmenter", Traits::kDescription,
            {rt::input<scan_t>("scan", "OS1_SCAN"), rt::input<imu_t>("imu", "OS1_IMU"),
             // The localizer's latest pose: places the ceiling points in the building's areas (option building).
             rt::input<pose_t>("pose", ""),  // only with segmenter.building; map it to FPLOC_POSE_LATEST
             rt::output<segments_t>("segments", "FPLOC_SEGMENTS")}};
  }

  void setup(rt::Context& ctx) override {
    ctx_ = &ctx;
    const auto& o = ctx.options<SegmenterOptions>();
    if (!o.algorithm().empty() && o.algorithm() != Traits::kAlgorithm)
      throw std::runtime_error(std::string("segmenter.algorithm: '") + o.algorithm() + "' is not served by fploc-" +
                               Traits::kExecutable + " (use " + Traits::kOther + ")");
    seg_ = Traits::make(o);
    use_imu_ = o.use_imu_prior() || !o.no_imu_attitude();  // the accelerometer: prior and/or gravity fusion
    if (o.has_building() && !o.building().file().empty()) use_building(ctx, o.building());
    out_ = ctx.advertise<segments_t>("segments");
    ctx.subscribe<scan_t>("scan", [this](const scan_t& m) { on_scan(m); });
    ctx.subscribe<imu_t>("imu", [this](const imu_t& m) {
      // IMU axes = sensor axes (OS-1: imu_to_sensor is a pure translation).
      const Eigen::Vector3d w(m.gyro[0], m.gyro[1], m.gyro[2]);
      const int64_t t = m.gyro_utime != 0 ? m.gyro_utime : m.utime;
      if (!w.allFinite())
        ctx_->error("imu seq " + std::to_string(m.seq) + ": non-finite gyro (ignored)");
      else
        seg_->add_gyro(w, t);  // de-skew of the sweep's rotation
      if (use_imu_) {
        const Eigen::Vector3d a(m.accel[0], m.accel[1], m.accel[2]);
        if (!a.allFinite())
          ctx_->error("imu seq " + std::to_string(m.seq) + ": non-finite accel (ignored)");
        else
          seg_->add_accel(a);
      }
      // A scan held for its sweep's IMU samples (scan_imu_sync.h) goes once they reach the sweep's end.
      sync_.on_imu(t, seg::ScanImuSync::Clock::now());
      show_holds();
    });
    // Live: scans whose IMU samples are later than kMaxHoldS go as they are, also when no scan follows (replay is
    // lock-step, its order fixed: samples, later scans or the end release them there).
    if (!ctx.composed())
      ctx.every(0.02, [this] {
        sync_.on_clock(seg::ScanImuSync::Clock::now());
        show_holds();
      });
  }

  // The last scans, when they were still waiting for their IMU samples.
  void shutdown() override { sync_.flush(seg::ScanImuSync::Clock::now()); }

 private:
  // The floor's area ceilings from the building file, and the pose feedback that places the ceiling points.
  void use_building(rt::Context& ctx, const PlanSource& src) {
    const std::string path = ctx.resolve_path(src.file());
    const Building b = load_building(path);
    if (b.floor_index(src.floor()) < 0)
      throw std::runtime_error("segmenter.building.floor: " + path + " has no floor '" + src.floor() + "'");
    // Every floor's ceilings; the pose's floor (pose_t.floor_index) picks the one used, from the configured one.
    for (const BuildingFloor& f : b.floors) {
      seg::AreaCeilingMap map;
      map.floor = f.name;
      map.default_height_m = f.ceiling_height;
      for (const auto& a : f.areas) map.areas.push_back({a.name, a.polygon, a.height, a.origin, a.slope});
      floors_.push_back(std::move(map));
    }
    floor_ = b.floor_index(src.floor());
    seg_->set_areas(floors_[size_t(floor_)]);
    const BuildingFloor& f = b.floors[size_t(floor_)];
    std::cerr << "[" << ctx.name() << "] " << path << " floor '" << f.name << "': ceiling " << f.ceiling_height
              << " m (0 = learned), " << f.areas.size() << " areas; plan pose from " << ctx.channel("pose") << "\n";
    if (ctx.channel("pose").empty())
      throw std::runtime_error("segmenter.building is set but the pose input is not connected (map it: input { port: \"pose\" channel: \"FPLOC_POSE_LATEST\" })");
    ctx.subscribe<pose_t>("pose", [this](const pose_t& m) {
      const Pose2 p = adapters::pose2_of(m);
      if (m.status == 2 || !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) return;  // LOST
      if (m.floor_index >= 0 && m.floor_index != floor_ && size_t(m.floor_index) < floors_.size()) {
        floor_ = m.floor_index;
        seg_->set_areas(floors_[size_t(floor_)]);  // that floor's ceilings (its learned heights start anew)
        std::cerr << "[" << ctx_->name() << "] floor '" << floors_[size_t(floor_)].floor << "': its ceiling areas\n";
      }
      seg_->set_plan_pose({m.utime, p.x, p.y, p.yaw, true});
    });
  }

  void on_scan(const scan_t& m) {
    Scan scan = sync_.take_spare();
    try {
      adapters::from_msg(m, scan);
    } catch (const std::exception& e) {
      // Bad message: say so downstream (status BAD_INPUT) and keep running; the scans before it go first.
      sync_.flush(seg::ScanImuSync::Clock::now());
      show_holds();
      segments_t msg;
      seg::Segmentation bad;
      bad.utime = m.utime;
      bad.seq = m.seq;
      bad.status = seg::SegStatus::kBadInput;
      bad.status_text = e.what();
      const auto& last = seg_->last();
      bad.roll = last.roll;
      bad.pitch = last.pitch;
      bad.z = last.z;
      bad.roll_pitch_sigma = last.roll_pitch_sigma;
      bad.z_sigma = last.z_sigma;
      bad.attitude_source = seg::AttitudeSource::kPrevious;
      ctx_->error(std::string("scan: ") + e.what());
      adapters::to_msg(bad, seq_++, msg);
      out_.publish(msg);
      return;
    }
    sync_.on_scan(std::move(scan), seg::ScanImuSync::Clock::now());
    show_holds();
  }

  // A scan through the segmenter, published (ScanImuSync calls it when the scan may go).
  void segment(const Scan& scan) {
    segments_t msg;
    const auto& s = seg_->process(scan);
    if (s.status == seg::SegStatus::kBadInput || s.status == seg::SegStatus::kEmpty)
      ctx_->error("scan seq " + std::to_string(scan.seq) + " on " + ctx_->channel("scan") + ": " + seg::to_string(s.status) +
                  ": " + s.status_text);
    adapters::to_msg(s, seq_++, msg);
    out_.publish(msg);
  }

  // The holds in the node's telemetry detail (the dashboard's "state detail"): a live IMU that lags the scans
  // shows there (the longest wait only live: replay has no wall time).
  void show_holds() {
    if (sync_.held() != shown_holds_) {
      shown_holds_ = sync_.held();
      ctx_->set_detail(sync_.describe(!ctx_->composed()));
    }
  }

  rt::Context* ctx_ = nullptr;
  std::unique_ptr<seg::Segmenter> seg_;
  rt::Publisher<segments_t> out_;
  seg::ScanImuSync sync_{[this](const Scan& scan) { segment(scan); }};  // scans wait for their IMU samples
  int64_t shown_holds_ = 0;
  int64_t seq_ = 0;
  bool use_imu_ = false;
  std::vector<seg::AreaCeilingMap> floors_;  // option building: every floor's ceilings
  int floor_ = 0;
};

}  // namespace fploc
