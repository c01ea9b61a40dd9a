#include "fploc/recording/ouster_packets.h"

namespace fploc::rec {

namespace {
constexpr size_t kMaxWaiting = 20000;  // ~2 s of 2048x10 packets
}

bool OusterPackets::set_metadata(const std::string& json, const std::string& source, std::string* err) {
  if (assembler_) return true;  // the driver republishes (latched); the first one counts
  try {
    assembler_ = std::make_unique<os1::FrameAssembler>(os1::parse_metadata(json, source));
  } catch (const std::exception& e) {
    if (err) *err = e.what();
    return false;
  }
  std::vector<Scan> frames_unused;
  auto waiting = std::move(waiting_);
  waiting_.clear();
  pending_.clear();
  for (auto& [t, p] : waiting) lidar(p.data(), p.size(), t, pending_);
  return true;
}

bool OusterPackets::add(const uint8_t* d, size_t n, int64_t t, std::vector<Scan>& frames, os1::ImuSample* imu) {
  if (!pending_.empty()) {
    for (auto& s : pending_) frames.push_back(std::move(s));
    pending_.clear();
  }
  if (n == os1::kImuPacketSize) {
    ++imu_packets;
    if (imu && os1::parse_imu_packet(d, n, *imu)) return true;
    ++bad_packets;
    last_error = "IMU packet with a non-finite value";
    return false;
  }
  ++lidar_packets;
  if (!assembler_) {
    if (waiting_.size() < kMaxWaiting) waiting_.push_back({t, std::vector<uint8_t>(d, d + n)});
    else ++waiting_dropped;
    return false;
  }
  lidar(d, n, t, frames);
  return false;
}

void OusterPackets::lidar(const uint8_t* d, size_t n, int64_t t, std::vector<Scan>& frames) {
  const size_t want = assembler_->format().lidar_packet_size();
  if (n == want + 1) n = want;  // ouster_ros 0.x: buf is one byte longer than the packet
  const size_t before = frames.size();
  const os1::PacketError e = assembler_->add_packet(d, n, frames);
  if (e != os1::PacketError::kNone && e != os1::PacketError::kInvalidColumns) {
    ++bad_packets;
    last_error = std::string("lidar packet: ") + os1::to_string(e) +
                 (e == os1::PacketError::kWrongSize ? " (" + std::to_string(n) + " B, metadata says " + std::to_string(want) + ")" : "");
  }
  for (size_t i = before; i < frames.size(); ++i) frame_times_ns.push_back(t);
}

void OusterPackets::flush(std::vector<Scan>& frames) {
  for (auto& s : pending_) frames.push_back(std::move(s));
  pending_.clear();
  if (!assembler_) return;
  const size_t before = frames.size();
  assembler_->flush(frames);
  for (size_t i = before; i < frames.size(); ++i) frame_times_ns.push_back(frame_times_ns.empty() ? 0 : frame_times_ns.back());
}

}  // namespace fploc::rec
