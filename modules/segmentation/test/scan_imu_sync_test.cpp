// ScanImuSync: a scan waits for the IMU samples of its sweep while the IMU stream is live, never otherwise.
#include <gtest/gtest.h>

#include <vector>

#include "fploc/segmentation/scan_imu_sync.h"

namespace {
using fploc::seg::ScanImuSync;
using Clock = ScanImuSync::Clock;

fploc::Scan sweep(int64_t t0, int width) {
  fploc::Scan s;
  s.resize(4, width);
  s.utime = t0;
  for (int c = 0; c < width; ++c) s.column_utime[size_t(c)] = t0 + int64_t(c) * 100000 / width;
  return s;
}

TEST(ScanImuSync, SweepEndIsTheLastValidColumnsTime) {
  fploc::Scan s = sweep(5000000, 1024);
  EXPECT_EQ(ScanImuSync::sweep_end(s), 5000000 + 1023 * 100000 / 1024);
  s.column_valid.back() = 0;  // the last column lost: the one before ends the sweep
  EXPECT_EQ(ScanImuSync::sweep_end(s), 5000000 + 1022 * 100000 / 1024);
  s.column_utime.assign(s.column_utime.size(), 0);  // no column times: the scan's own
  EXPECT_EQ(ScanImuSync::sweep_end(s), 5000000);
}

TEST(ScanImuSync, HoldsAScanUntilItsSweepsSamplesWhileTheImuIsLive) {
  ScanImuSync sync([](const fploc::Scan&) {});
  const Clock::time_point t0{};
  const fploc::Scan s = sweep(10000000, 1024);
  const int64_t end = ScanImuSync::sweep_end(s);
  EXPECT_TRUE(sync.ready(s.utime, end)) << "no IMU yet: never held";
  for (int64_t t = 9000000; t <= 10000000; t += 10000) sync.on_imu(t, t0);  // samples up to the sweep's start (live)
  EXPECT_FALSE(sync.ready(s.utime, end)) << "the sweep's samples are still to come";
  for (int64_t t = 10010000; t <= 10070000; t += 10000) sync.on_imu(t, t0);
  EXPECT_FALSE(sync.ready(s.utime, end)) << "samples up to 30 ms before the sweep's end";
  sync.on_imu(10080000, t0);  // 20 ms before the end: what the de-skew accepts (the rate held beyond the last sample)
  EXPECT_TRUE(sync.ready(s.utime, end));
  sync.on_imu(10100000, t0);
  sync.on_imu(10050000, t0);  // out of order: the newest stays
  EXPECT_EQ(sync.last_imu(), 10100000);
}

TEST(ScanImuSync, NeverHoldsWhenTheImuStopped) {
  ScanImuSync sync([](const fploc::Scan&) {}, 1000000);
  const Clock::time_point t0{};
  sync.on_imu(3000000, t0);  // the last sample 7 s before the scan: the stream stopped
  const fploc::Scan s = sweep(10000000, 64);
  EXPECT_TRUE(sync.ready(s.utime, ScanImuSync::sweep_end(s)));
  sync.on_imu(9100000, t0);  // 0.9 s before: live again
  EXPECT_FALSE(sync.ready(s.utime, ScanImuSync::sweep_end(s)));
}

// The queue: scans go in arrival order, each when the IMU reaches its sweep, or without its samples once a later
// scan starts more than kMaxHoldUs after its end, or after kMaxHoldS of wall time (a fake clock here).
TEST(ScanImuSync, HeldScansGoInOrderWithTheirSamplesOrAfterTheHold) {
  std::vector<int64_t> went;
  ScanImuSync sync([&](const fploc::Scan& s) { went.push_back(s.seq); });
  const Clock::time_point t0{};
  auto scan = [](int64_t seq) {
    fploc::Scan s = sweep(10000000 + seq * 100000, 64);
    s.seq = seq;
    return s;
  };
  for (int64_t t = 9500000; t <= 10000000; t += 10000) sync.on_imu(t, t0);  // live, up to scan 0's start
  sync.on_scan(scan(0), t0);
  sync.on_scan(scan(1), t0);
  EXPECT_TRUE(went.empty()) << "both wait for their sweeps' samples";
  EXPECT_EQ(sync.describe(true), "");
  sync.on_imu(10090000, t0);  // within 20 ms of scan 0's end: it goes; scan 1 keeps waiting
  EXPECT_EQ(went, (std::vector<int64_t>{0}));
  sync.on_imu(10190000, t0);
  EXPECT_EQ(went, (std::vector<int64_t>{0, 1}));
  EXPECT_EQ(sync.held(), 2);
  EXPECT_EQ(sync.without_samples(), 0);
  EXPECT_EQ(sync.describe(false), "IMU late: 2 scans waited for their sweep's samples");

  // The IMU stops coming: scans 2..8 wait until a later scan starts more than 0.5 s after the oldest's end.
  for (int64_t k = 2; k <= 8; ++k) sync.on_scan(scan(k), t0);
  EXPECT_EQ(went, (std::vector<int64_t>{0, 1, 2})) << "scan 8 starts 0.5 s + 1 sweep after scan 2's end";
  EXPECT_EQ(sync.without_samples(), 1);
  // Wall time: 0.4 s keeps them, 0.6 s lets every one go, in order.
  sync.on_clock(t0 + std::chrono::milliseconds(400));
  EXPECT_EQ(went.size(), 3u);
  sync.on_clock(t0 + std::chrono::milliseconds(600));
  EXPECT_EQ(went, (std::vector<int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(sync.describe(true), "IMU late: 9 scans waited for their sweep's samples (longest 600 ms), 7 went without them");

  // A scan the IMU already covers goes at once; flush lets a held one go (shutdown).
  sync.on_imu(11000000, t0);
  sync.on_scan(scan(9), t0);
  EXPECT_EQ(went.back(), 9);
  EXPECT_EQ(sync.held(), 9) << "scan 9 did not wait";
  sync.on_scan(scan(10), t0);
  sync.on_scan(scan(11), t0);
  EXPECT_EQ(went.back(), 9);
  sync.flush(t0);
  EXPECT_EQ(went, (std::vector<int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
  EXPECT_EQ(sync.take_spare().width, 64) << "a scan that went, for reuse";
}

}  // namespace
