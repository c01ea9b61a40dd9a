// The simulated sequence the perception benchmarks run on (perception_bench, perception_ratio_bench): OS-1-64
// scans of room-small-loop-medium (real beam angles from ../shared when present), and consecutive frames with
// every IMU sample up to each sweep's end, as the segmenter node receives them.
#pragma once
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"

namespace fploc::bench {

inline sim::SimulatorOptions sequence_options() {
  sim::SimulatorOptions o;
  o.scenario = "room-small-loop-medium";
  o.shared_dir = FPLOC_SHARED_DIR;
  return o;
}

struct ImuFrame {
  Scan scan;
  std::vector<std::pair<int64_t, sim::ImuSample>> imu;  // (utime, sample): those up to the sweep's end
};

// `count` consecutive frames from frame `first` on (the sensor moving), with the IMU samples since 0.2 s before
// the first sweep: feed each frame's samples (add_gyro, add_accel), then its scan.
inline std::vector<ImuFrame> imu_frames(int first, size_t count) {
  const sim::SimulatorOptions o = sequence_options();
  sim::Simulator sim(FloorPlan{}, o);
  const auto& imu = sim.imu();
  size_t next = 0;
  while (next < imu.size() && imu[next].t < sim.frame_time(first) - o.t0_s - 0.2) ++next;
  std::vector<ImuFrame> out;
  sim::SimScan s;
  for (int k = first; k < sim.num_frames() && out.size() < count; ++k) {
    sim.frame(k, s);
    ImuFrame fr;
    fr.scan = s.scan;
    const double end = sim.frame_time(k) - o.t0_s + 1.0 / o.rate_hz;
    for (; next < imu.size() && imu[next].t <= end; ++next)
      fr.imu.emplace_back(int64_t(std::llround((o.t0_s + imu[next].t) * 1e6)), imu[next]);
    out.push_back(std::move(fr));
  }
  return out;
}

// A frame's IMU samples into the segmenter, as the segmenter node gives them (before the frame's scan).
inline void feed_imu(seg::Segmenter& sg, const ImuFrame& f) {
  for (const auto& [utime, smp] : f.imu) {
    sg.add_gyro(smp.gyro, utime);
    sg.add_accel(smp.accel);
  }
}

}  // namespace fploc::bench
