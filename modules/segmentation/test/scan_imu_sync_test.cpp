// ScanImuSync: a scan waits for the IMU samples of its sweep while the IMU stream is live, never otherwise.
#include <gtest/gtest.h>

#include "fploc/segmentation/scan_imu_sync.h"

namespace {
using fploc::seg::ScanImuSync;

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
  ScanImuSync sync;
  const fploc::Scan s = sweep(10000000, 1024);
  const int64_t end = ScanImuSync::sweep_end(s);
  EXPECT_TRUE(sync.ready(s.utime, end)) << "no IMU yet: never held";
  for (int64_t t = 9000000; t <= 10000000; t += 10000) sync.on_imu(t);  // samples up to the sweep's start (live)
  EXPECT_FALSE(sync.ready(s.utime, end)) << "the sweep's samples are still to come";
  for (int64_t t = 10010000; t <= 10070000; t += 10000) sync.on_imu(t);
  EXPECT_FALSE(sync.ready(s.utime, end)) << "samples up to 30 ms before the sweep's end";
  sync.on_imu(10080000);  // 20 ms before the end: what the de-skew accepts (the rate held beyond the last sample)
  EXPECT_TRUE(sync.ready(s.utime, end));
  sync.on_imu(10100000);
  sync.on_imu(10050000);  // out of order: the newest stays
  EXPECT_EQ(sync.last_imu(), 10100000);
}

TEST(ScanImuSync, NeverHoldsWhenTheImuStopped) {
  ScanImuSync sync(1000000);
  sync.on_imu(3000000);  // the last sample 7 s before the scan: the stream stopped
  const fploc::Scan s = sweep(10000000, 64);
  EXPECT_TRUE(sync.ready(s.utime, ScanImuSync::sweep_end(s)));
  sync.on_imu(9100000);  // 0.9 s before: live again
  EXPECT_FALSE(sync.ready(s.utime, ScanImuSync::sweep_end(s)));
}

}  // namespace
