// Xsens MTi (e.g. MTi-30, the paper's IMU) Xbus protocol: MTData2 messages from a byte stream (serial
// port or a recording). Not Ouster, but it feeds the same imu driver, so it lives beside the Ouster IMU
// parser until there is an imu module. Big-endian on the wire.
//   Xbus message: 0xFA (preamble), 0xFF (bus id), MID, LEN (0xFF: a 2-byte extended length follows),
//   payload, checksum (sum of every byte after the preamble, checksum included, is 0 mod 256).
//   MTData2 (MID 0x36) payload: items of [XDI u16][size u8][data]. Used: PacketCounter 0x1020,
//   SampleTimeFine 0x1060 (10 kHz ticks), Acceleration 0x4020 [m/s^2], RateOfTurn 0x8020 [rad/s];
//   precision from the XDI's low 2 bits (float32, fp12.20, fp16.32, float64).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace fploc::os1 {

struct XsensSample {
  bool has_counter = false, has_time = false, has_accel = false, has_gyro = false;
  uint16_t packet_counter = 0;
  uint32_t sample_time_fine = 0;  // 10 kHz ticks
  std::array<double, 3> accel{};  // m/s^2
  std::array<double, 3> gyro{};   // rad/s
};

constexpr uint8_t kXbusMtData2 = 0x36;

// Parses an MTData2 payload. False when an item runs past the end or a known item has a wrong size.
bool parse_mtdata2(const uint8_t* payload, size_t size, XsensSample& out);
// A complete Xbus message (preamble, bus id 0xFF, MID, length, payload, checksum).
std::vector<uint8_t> xbus_message(uint8_t mid, const std::vector<uint8_t>& payload);

struct XbusStats {
  uint64_t messages = 0;        // checksummed messages
  uint64_t samples = 0;         // MTData2 messages decoded
  uint64_t checksum_errors = 0;
  uint64_t bad_payloads = 0;    // MTData2 that did not parse
  uint64_t skipped_bytes = 0;   // bytes dropped while looking for a preamble
  uint64_t other_messages = 0;  // valid messages that are not MTData2
};

// Incremental Xbus framing over a byte stream; resynchronises on garbage.
class XbusParser {
 public:
  void feed(const uint8_t* data, size_t size, const std::function<void(const XsensSample&)>& fn);
  const XbusStats& stats() const { return stats_; }

 private:
  std::vector<uint8_t> buf_;
  XbusStats stats_;
};

}  // namespace fploc::os1
