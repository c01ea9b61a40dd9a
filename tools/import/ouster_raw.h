// ouster_ros/PacketMsg streams written as they are (fploc import's default for Ouster bags): every
// lidar and IMU packet becomes one os1_packet_t (OS1_LIDAR_PACKETS, OS1_IMU_PACKETS) and the metadata
// JSON one os1_metadata_t (OS1_METADATA); the OS-1 and IMU drivers decode them on replay (graph
// graphs/replay-packets.pbtxt) exactly as they decode the live sensor. No decoding here, so the import
// runs at the speed of the file. The metadata is written before any lidar packet (packets that come
// first in the bag wait for it, up to a bound), and ouster_ros 0.x's one extra byte after a lidar
// packet is dropped, so the log holds the sensor's packets byte for byte.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "lcm_log.h"

namespace fploc::import {

class OusterRawWriter {
 public:
  // log == nullptr: count only (no --out).
  explicit OusterRawWriter(LcmLog* log) : log_(log) {}
  // The metadata JSON (topic or --metadata file): checked with the OS-1 metadata parser; the first good
  // one is written (the driver republishes it latched). False with *err when unusable.
  bool metadata(const std::string& json, const std::string& source, int64_t time_ns, std::string* err);
  // Which channel a packet goes to: its topic's (ouster_ros' lidar_packets / imu_packets), or by its size for
  // a topic named otherwise (48 B: IMU).
  enum class Route { kBySize, kLidar, kImu };
  // One PacketMsg buf; stable: d stays valid until the log is closed (written from where it is). An IMU
  // packet must be 48 B (the caller reports and skips another size on the IMU topic).
  void packet(const uint8_t* d, size_t n, int64_t time_ns, bool stable = false, Route route = Route::kBySize);
  bool has_metadata() const { return lidar_size_ > 0; }
  // The recording's metadata did not parse: the lidar packets that wait for it and the ones that follow are
  // written as they are, without it (the OS-1 driver's metadata option can supply it on replay).
  void without_metadata();
  uint64_t written_without_metadata = 0;

  std::string lidar_channel = "OS1_LIDAR_PACKETS", imu_channel = "OS1_IMU_PACKETS", metadata_channel = "OS1_METADATA";
  uint64_t lidar_packets = 0, imu_packets = 0, other_size = 0, waiting_dropped = 0;
  std::string sensor, udp_profile;
  int pixels_per_column = 0, columns_per_frame = 0;
  size_t lidar_size() const { return lidar_size_; }

 private:
  void write(const std::string& ch, int64_t time_ns, const uint8_t* d, size_t n, bool stable);
  LcmLog* log_;
  size_t lidar_size_ = 0;
  bool without_metadata_ = false;
  std::vector<std::pair<int64_t, std::vector<uint8_t>>> waiting_;
};

}  // namespace fploc::import
