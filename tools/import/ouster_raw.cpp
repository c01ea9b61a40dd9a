#include "ouster_raw.h"

#include <fploc/os1_metadata_t.hpp>
#include <fploc/os1_packet_t.hpp>

#include <algorithm>
#include <cstring>

#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"

namespace fploc::import {

namespace {
constexpr size_t kMaxWaiting = 20000;  // as the decoding import: ~2 s of 2048x10 packets
}

bool OusterRawWriter::metadata(const std::string& json, const std::string& source, int64_t time_ns, std::string* err) {
  if (lidar_size_) return true;
  os1::SensorInfo info;
  try {
    info = os1::parse_metadata(json, source);
  } catch (const std::exception& e) {
    if (err) *err = e.what();
    return false;
  }
  lidar_size_ = os1::PacketFormat::from(info).lidar_packet_size();
  sensor = info.sensor_name();
  udp_profile = os1::to_string(info.profile);
  pixels_per_column = info.pixels_per_column;
  columns_per_frame = info.columns_per_frame;
  if (!waiting_.empty()) time_ns = std::min(time_ns, waiting_.front().first);  // before the packets that waited
  if (log_) {
    os1_metadata_t m;
    m.utime = time_ns / 1000;
    m.source = source;
    m.json = json;
    log_->write(metadata_channel, m.utime, m);
  }
  auto waiting = std::move(waiting_);
  waiting_.clear();
  for (auto& [t, p] : waiting) packet(p.data(), p.size(), t), --lidar_packets;  // counted when they came
  return true;
}

void OusterRawWriter::packet(const uint8_t* d, size_t n, int64_t time_ns, bool stable, Route route) {
  if (route == Route::kImu || (route == Route::kBySize && n == os1::kImuPacketSize)) {
    ++imu_packets;
    write(imu_channel, time_ns, d, n, stable);
    return;
  }
  ++lidar_packets;
  if (!lidar_size_ && without_metadata_) {
    ++written_without_metadata;
    write(lidar_channel, time_ns, d, n, stable);
    return;
  }
  if (!lidar_size_) {
    if (waiting_.size() < kMaxWaiting) waiting_.push_back({time_ns, std::vector<uint8_t>(d, d + n)});
    else ++waiting_dropped;
    return;
  }
  if (n == lidar_size_ + 1) n = lidar_size_;  // ouster_ros 0.x: buf is one byte longer than the packet
  if (n != lidar_size_) ++other_size;         // written as it is: the driver reports it, as it would live
  write(lidar_channel, time_ns, d, n, stable);
}

void OusterRawWriter::without_metadata() {
  if (lidar_size_ || without_metadata_) return;
  without_metadata_ = true;
  auto waiting = std::move(waiting_);
  waiting_.clear();
  for (auto& [t, p] : waiting) packet(p.data(), p.size(), t), --lidar_packets;  // counted when they came
}

void OusterRawWriter::write(const std::string& ch, int64_t time_ns, const uint8_t* d, size_t n, bool stable) {
  if (!log_) return;
  // os1_packet_t: fingerprint, utime, size, data (big-endian), the payload straight from the recording.
  const int64_t utime = time_ns / 1000;
  uint8_t h[20];
  const uint64_t hash = __builtin_bswap64(uint64_t(os1_packet_t::getHash())), ut = __builtin_bswap64(uint64_t(utime));
  const uint32_t sz = __builtin_bswap32(uint32_t(n));
  std::memcpy(h, &hash, 8);
  std::memcpy(h + 8, &ut, 8);
  std::memcpy(h + 16, &sz, 4);
  log_->write_parts(ch, utime, h, sizeof h, d, n, stable);
}

}  // namespace fploc::import
