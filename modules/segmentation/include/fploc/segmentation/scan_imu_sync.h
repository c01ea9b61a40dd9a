#pragma once
// When a scan may be segmented: once the IMU samples of its sweep are in.
//
// The segmenter de-skews a sweep with the gyro and carries gravity from scan to scan with it
// (gyro_deskew.h, gravity_fusion.h); both need gyro samples up to the sweep's end. A log written by the
// simulator or a recorder has every IMU sample before the scan that ends after it, but live the two streams
// come through different processes and sockets: on a busy machine the IMU samples of a whole sweep (10 at
// 100 Hz) arrived 50-100 ms after the scan. Segmented at once, such a scan had no gyro for its sweep: no
// de-skew, and a plane change on a ramp taken as level (the sensor's pitch 7 deg off for 50 s in a live demo
// run; the same log replayed in lock-step gave the same error).
//
// ScanImuSync holds scans back, in arrival order, while the IMU stream is live (a sample within live_window of
// the scan's start) and has not reached the scan's sweep end (within the 20 ms the de-skew and the fusion
// accept beyond the last sample, segmenter_constants.h kGyroEdgeUs: a log in the simulator's order is never
// held). A held scan goes when a sample reaches it, or as it is once a later scan starts more than kMaxHoldUs
// after its end or (live, on_clock) after kMaxHoldS of wall time: the IMU is then later than any lag seen.
// Without an IMU, or with a stream that stopped, scans are never held. No transport here: the segmenter node
// feeds it and segments what it emits; the wall clock is passed in (a fake one in the tests).
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "fploc/core/scan.h"

namespace fploc::seg {

class ScanImuSync {
 public:
  using Clock = std::chrono::steady_clock;
  // A held scan goes without its samples after this long: wall time (live), and sensor time between its sweep's
  // end and the newest scan's start. The IMU's arrival delay in live runs on a busy machine: p99 150-270 ms,
  // at most 480 ms (docs/notes/height.md, "Eleventh round").
  static constexpr double kMaxHoldS = 0.5;
  static constexpr int64_t kMaxHoldUs = 500000;

  // emit: called with every scan that goes (now or released later), in arrival order.
  explicit ScanImuSync(std::function<void(const Scan&)> emit, int64_t live_window_us = 1000000)
      : emit_(std::move(emit)), live_window_us_(live_window_us) {}

  // An IMU sample's time (the gyro's stamp, as the segmenter gets it): the held scans it completes go. now: the
  // wall time (as in every call below; only the telemetry's longest hold and on_clock read it).
  void on_imu(int64_t utime, Clock::time_point now);
  // A scan: goes now, or is held (also when older scans are held: the order is kept).
  void on_scan(Scan&& scan, Clock::time_point now);
  // Live, periodically: scans held longer than kMaxHoldS of wall time go without their samples.
  void on_clock(Clock::time_point now);
  // Every held scan goes as it is (shutdown; a message that is not a scan).
  void flush(Clock::time_point now);
  // A scan to fill (one that went before: its arrays keep their capacity).
  Scan take_spare();

  // What happened so far: scans held, those of them that went without their samples, the longest hold (wall
  // time); as one line for telemetry ("" before the first hold; with_wait: the longest hold too, live only).
  int64_t held() const { return held_count_; }
  int64_t without_samples() const { return without_samples_; }
  std::string describe(bool with_wait) const;

  int64_t last_imu() const { return last_imu_; }
  // The sweep's end: the last valid column's time, else the scan's time (no column times: nothing to wait for).
  static int64_t sweep_end(const Scan& scan);
  // True when a scan whose sweep ends at end_utime (and starts at start_utime) can be segmented now: no IMU
  // seen, the stream silent for longer than live_window before the sweep, or a sample within the de-skew's
  // tolerance of its end.
  bool ready(int64_t start_utime, int64_t end_utime) const;

 private:
  struct Held {
    Scan scan;
    int64_t end = 0;  // its sweep's end
    Clock::time_point since;
  };
  void release(bool with_samples, Clock::time_point now);

  std::function<void(const Scan&)> emit_;
  int64_t live_window_us_;
  int64_t last_imu_ = 0;
  std::deque<Held> held_;    // in arrival order
  std::vector<Scan> spare_;  // scans that went, for reuse
  int64_t held_count_ = 0, without_samples_ = 0;
  double max_wait_s_ = 0;
};

}  // namespace fploc::seg
