// ouster_ros/PacketMsg streams (lidar and IMU packets, plus the metadata JSON the driver publishes on
// its metadata topic) through fploc's own OS-1 decoder: a bag gives the scans the live driver gives.
// Lidar packets that arrive before any metadata are kept (up to a bound) and decoded once it arrives.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fploc/core/scan.h"
#include "fploc/os1/packet.h"

namespace fploc::rec {

class OusterPackets {
 public:
  // The sensor metadata JSON (the metadata topic or a file); false with *err when unusable.
  bool set_metadata(const std::string& json, const std::string& source, std::string* err);
  bool has_metadata() const { return assembler_ != nullptr; }
  const os1::SensorInfo* info() const { return assembler_ ? &assembler_->info() : nullptr; }

  // One ouster_ros/PacketMsg buf: 48 B are IMU packets (returned in imu with true), anything else a
  // lidar packet (completed frames are appended to frames). ouster_ros 0.x sends one extra byte after
  // a lidar packet; it is ignored.
  bool add(const uint8_t* buf, size_t n, int64_t time_ns, std::vector<Scan>& frames, os1::ImuSample* imu);
  void flush(std::vector<Scan>& frames);
  // Hands a consumed frame's buffers back (avoids allocating at the frame rate).
  void recycle(Scan&& s) {
    if (assembler_) assembler_->recycle(std::move(s));
  }

  uint64_t lidar_packets = 0, imu_packets = 0, bad_packets = 0, waiting_dropped = 0;
  std::string last_error;  // the latest packet problem (counted in bad_packets)
  // Record time of the packet that completed each frame, in the order frames were produced.
  std::vector<int64_t> frame_times_ns;

 private:
  void lidar(const uint8_t* d, size_t n, int64_t t, std::vector<Scan>& frames);
  std::unique_ptr<os1::FrameAssembler> assembler_;
  std::vector<std::pair<int64_t, std::vector<uint8_t>>> waiting_;
  std::vector<Scan> pending_;  // frames completed by packets that waited for the metadata
};

}  // namespace fploc::rec
