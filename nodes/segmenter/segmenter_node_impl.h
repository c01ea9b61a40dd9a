// The segmenter node body shared by fploc-segmenter (paper) and fploc-segmenter-ransac (PCL): same ports,
// same message, same options field `segmenter`, so a graph swaps the executable only.
#pragma once
#include <fploc/imu_t.hpp>
#include <fploc/pose_t.hpp>
#include <fploc/scan_t.hpp>
#include <fploc/segments_t.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
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
      if (!w.allFinite())
        ctx_->error("imu seq " + std::to_string(m.seq) + ": non-finite gyro (ignored)");
      else
        seg_->add_gyro(w, m.gyro_utime != 0 ? m.gyro_utime : m.utime);  // de-skew of the sweep's rotation
      // A scan held for its sweep's IMU samples (scan_imu_sync.h) goes once they reach the sweep's end.
      sync_.on_imu(m.gyro_utime != 0 ? m.gyro_utime : m.utime);
      if (use_imu_) {
        const Eigen::Vector3d a(m.accel[0], m.accel[1], m.accel[2]);
        if (!a.allFinite())
          ctx_->error("imu seq " + std::to_string(m.seq) + ": non-finite accel (ignored)");
        else
          seg_->add_accel(a);
      }
      while (!held_.empty() && sync_.ready(held_.front().scan.utime, held_.front().end)) release(true);
    });
    // Live: a scan whose IMU samples are later than kMaxHoldS goes as it is, also when no scan follows (replay
    // is lock-step, its order fixed: samples, later scans or the end release it there).
    if (!ctx.composed())
      ctx.every(0.02, [this] {
        while (!held_.empty() && std::chrono::duration<double>(std::chrono::steady_clock::now() - held_.front().since)
                                         .count() > seg::ScanImuSync::kMaxHoldS)
          release(false);
      });
  }

  // The last scan, when it was still waiting for its IMU samples.
  void shutdown() override {
    while (!held_.empty()) release(false);
  }

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
    Scan scan;
    if (!spare_.empty()) {  // a recycled scan: its arrays keep their capacity
      scan = std::move(spare_.back());
      spare_.pop_back();
    }
    try {
      adapters::from_msg(m, scan);
    } catch (const std::exception& e) {
      // Bad message: say so downstream (status BAD_INPUT) and keep running; the scans before it go first.
      while (!held_.empty()) release(false);
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
      spare_.push_back(std::move(scan));
      return;
    }
    const int64_t end = seg::ScanImuSync::sweep_end(scan);
    if (held_.empty() && sync_.ready(scan.utime, end)) {
      segment(scan);
      spare_.push_back(std::move(scan));
      return;
    }
    held_.push_back({std::move(scan), end, std::chrono::steady_clock::now()});
    // Scans held longer than kMaxHoldS in sensor time (the newest's start after the oldest's end by more): the IMU
    // is later than any lag seen, the oldest go as they are.
    while (held_.size() > 1 && held_.back().scan.utime - held_.front().end > seg::ScanImuSync::kMaxHoldUs) release(false);
  }

  // The oldest held scan goes: with its sweep's samples, or without them (the IMU too late). The counts are the
  // node's telemetry detail (the dashboard's "state detail"): a live IMU that lags the scans shows there.
  void release(bool with_samples) {
    Held h = std::move(held_.front());
    held_.pop_front();
    ++held_count_;
    if (!with_samples) ++without_samples_;
    std::string d = "IMU late: " + std::to_string(held_count_) + (held_count_ == 1 ? " scan" : " scans") +
                    " waited for their sweep's samples";
    if (!ctx_->composed()) {
      const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - h.since).count();
      max_wait_s_ = std::max(max_wait_s_, w);
      d += " (longest " + std::to_string(int(std::lround(1000 * max_wait_s_))) + " ms)";
    }
    if (without_samples_ > 0) d += ", " + std::to_string(without_samples_) + " went without them";
    ctx_->set_detail(d);
    segment(h.scan);
    spare_.push_back(std::move(h.scan));
  }

  // A scan through the segmenter, published.
  void segment(const Scan& scan) {
    segments_t msg;
    const auto& s = seg_->process(scan);
    if (s.status == seg::SegStatus::kBadInput || s.status == seg::SegStatus::kEmpty)
      ctx_->error("scan seq " + std::to_string(scan.seq) + " on " + ctx_->channel("scan") + ": " + seg::to_string(s.status) +
                  ": " + s.status_text);
    adapters::to_msg(s, seq_++, msg);
    out_.publish(msg);
  }

  // A scan waiting for its sweep's IMU samples (scan_imu_sync.h).
  struct Held {
    Scan scan;
    int64_t end = 0;  // its sweep's end
    std::chrono::steady_clock::time_point since;
  };

  rt::Context* ctx_ = nullptr;
  std::unique_ptr<seg::Segmenter> seg_;
  rt::Publisher<segments_t> out_;
  std::deque<Held> held_;    // in arrival order, until their sweep's IMU samples are in
  std::vector<Scan> spare_;  // scans segmented, for reuse
  seg::ScanImuSync sync_;
  int64_t held_count_ = 0, without_samples_ = 0;  // scans held, and of those released without their samples
  double max_wait_s_ = 0;                         // live: the longest hold (wall time)
  int64_t seq_ = 0;
  bool use_imu_ = false;
  std::vector<seg::AreaCeilingMap> floors_;  // option building: every floor's ceilings
  int floor_ = 0;
};

}  // namespace fploc
