#include "fploc/segmentation/scan_imu_sync.h"

#include <algorithm>
#include <cmath>

#include "segmenter_constants.h"

namespace fploc::seg {

int64_t ScanImuSync::sweep_end(const Scan& scan) {
  const bool cvalid = scan.column_valid.size() == scan.column_utime.size();
  int64_t end = scan.utime;
  for (size_t c = 0; c < scan.column_utime.size(); ++c)
    if (scan.column_utime[c] != 0 && (!cvalid || scan.column_valid[c])) end = std::max(end, scan.column_utime[c]);
  return end;
}

bool ScanImuSync::ready(int64_t start_utime, int64_t end_utime) const {
  if (last_imu_ <= 0 || last_imu_ < start_utime - live_window_us_) return true;
  return last_imu_ >= end_utime - k::kGyroEdgeUs;
}

void ScanImuSync::on_imu(int64_t utime, Clock::time_point now) {
  if (utime > last_imu_) last_imu_ = utime;
  while (!held_.empty() && ready(held_.front().scan.utime, held_.front().end)) release(true, now);
}

void ScanImuSync::on_scan(Scan&& scan, Clock::time_point now) {
  const int64_t end = sweep_end(scan);
  if (held_.empty() && ready(scan.utime, end)) {
    emit_(scan);
    spare_.push_back(std::move(scan));
    return;
  }
  held_.push_back({std::move(scan), end, now});
  // Held longer than kMaxHoldUs in sensor time (the newest's start after the oldest's end by more): the IMU is
  // later than any lag seen, the oldest go as they are.
  while (held_.size() > 1 && held_.back().scan.utime - held_.front().end > kMaxHoldUs) release(false, now);
}

void ScanImuSync::on_clock(Clock::time_point now) {
  while (!held_.empty() && std::chrono::duration<double>(now - held_.front().since).count() > kMaxHoldS)
    release(false, now);
}

void ScanImuSync::flush(Clock::time_point now) {
  while (!held_.empty()) release(false, now);
}

Scan ScanImuSync::take_spare() {
  if (spare_.empty()) return Scan{};
  Scan s = std::move(spare_.back());
  spare_.pop_back();
  return s;
}

void ScanImuSync::release(bool with_samples, Clock::time_point now) {
  Held h = std::move(held_.front());
  held_.pop_front();
  ++held_count_;
  if (!with_samples) ++without_samples_;
  max_wait_s_ = std::max(max_wait_s_, std::chrono::duration<double>(now - h.since).count());
  emit_(h.scan);
  spare_.push_back(std::move(h.scan));
}

std::string ScanImuSync::describe(bool with_wait) const {
  if (held_count_ == 0) return "";
  std::string d = "IMU late: " + std::to_string(held_count_) + (held_count_ == 1 ? " scan" : " scans") +
                  " waited for their sweep's samples";
  if (with_wait) d += " (longest " + std::to_string(int(std::lround(1000 * max_wait_s_))) + " ms)";
  if (without_samples_ > 0) d += ", " + std::to_string(without_samples_) + " went without them";
  return d;
}

}  // namespace fploc::seg
