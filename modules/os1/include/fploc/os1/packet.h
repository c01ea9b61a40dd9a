// Ouster UDP packets: lidar (LEGACY, RNG19_RFL8_SIG16_NIR16 and the
// low-data-rate RNG15_RFL8_NIR8 profiles) and IMU (48 B), parse and encode,
// plus FrameAssembler which turns a stream of lidar packets into Scans (one per frame_id).
// All multi-byte fields are little-endian on the wire. Nothing here throws or crashes on garbage: bad
// packets are rejected with a reason and counted.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/core/scan.h"
#include "fploc/os1/metadata.h"

namespace fploc::os1 {

constexpr size_t kImuPacketSize = 48;
constexpr uint32_t kEncoderTicksPerRev = 90112;

// Byte layout of a lidar packet for one profile and beam count.
struct PacketFormat {
  UdpProfile profile = UdpProfile::kLegacy;
  int pixels_per_column = 64;
  int columns_per_packet = 16;
  int columns_per_frame = 1024;

  static PacketFormat from(const SensorInfo& info);
  size_t packet_header_size() const { return profile == UdpProfile::kLegacy ? 0 : 32; }
  size_t packet_footer_size() const { return profile == UdpProfile::kLegacy ? 0 : 32; }
  size_t column_header_size() const { return profile == UdpProfile::kLegacy ? 16 : 12; }
  size_t column_footer_size() const { return profile == UdpProfile::kLegacy ? 4 : 0; }
  size_t pixel_size() const { return profile == UdpProfile::kRng15Rfl8Nir8 ? 4 : 12; }
  size_t column_size() const { return column_header_size() + size_t(pixels_per_column) * pixel_size() + column_footer_size(); }
  size_t lidar_packet_size() const {
    return packet_header_size() + size_t(columns_per_packet) * column_size() + packet_footer_size();
  }
};

enum class PacketError {
  kNone = 0,
  kWrongSize,          // not the lidar packet size of this format
  kBadMeasurementId,   // measurement id >= columns_per_frame
  kStaleFrame,         // packet of a frame that was already published (late / reordered): dropped
  kDuplicateColumn,    // column already received for this frame: dropped
  kInvalidColumns,     // parsed, but some columns had the invalid status bit
};
const char* to_string(PacketError e);

// One decoded column header.
struct ColumnHeader {
  uint64_t timestamp_ns = 0;
  uint16_t measurement_id = 0;
  uint16_t frame_id = 0;
  uint32_t encoder_count = 0;  // legacy only
  uint32_t status = 0;         // legacy: 32-bit status word; non-legacy: 16-bit status
  bool valid() const { return (status & 1u) != 0; }
};

// Read access to a packet already checked for size. Pixel getters take (column 0..15, beam).
class LidarPacketView {
 public:
  // Returns false (and sets *err) when `size` is not the format's packet size.
  bool reset(const PacketFormat& f, const uint8_t* data, size_t size, PacketError* err = nullptr);
  ColumnHeader column(int c) const;
  uint16_t packet_frame_id() const;  // non-legacy: from the packet header; legacy: column 0's
  uint32_t range_mm(int c, int beam) const;
  uint16_t signal(int c, int beam) const;
  uint16_t reflectivity(int c, int beam) const;
  uint16_t near_ir(int c, int beam) const;
  const uint8_t* pixel(int c, int beam) const {
    return data_ + f_.packet_header_size() + size_t(c) * f_.column_size() + f_.column_header_size() + size_t(beam) * 12;
  }
  const PacketFormat& format() const { return f_; }

 private:
  PacketFormat f_;
  const uint8_t* data_ = nullptr;
};

// Encodes columns [first_column, first_column + columns_per_packet) of `scan` (staggered; column index =
// measurement id) into one packet of `f`. Column timestamps are scan.column_utime * 1000 ns, encoder
// counts measurement_id * 90112 / W, status valid (0xFFFFFFFF legacy, 0x1 otherwise) when column_valid.
// Ranges are clipped to the profile's bits (20 legacy, 19 RNG19; RNG15 stores range/8 in 15 bits). `out` is resized to the packet size.
void encode_lidar_packet(const Scan& scan, int first_column, uint16_t frame_id, const PacketFormat& f,
                         std::vector<uint8_t>& out);
// All packets of one frame (W / columns_per_packet of them), in measurement-id order.
void encode_frame(const Scan& scan, uint16_t frame_id, const PacketFormat& f, std::vector<std::vector<uint8_t>>& out);

// ---- IMU --------------------------------------------------------------------------------------
struct ImuSample {
  uint64_t sys_ts_ns = 0, accel_ts_ns = 0, gyro_ts_ns = 0;
  std::array<double, 3> accel_mps2{};  // SI
  std::array<double, 3> gyro_radps{};
};
constexpr double kStandardGravity = 9.80665;
// Returns false when size != 48 or a value is not finite.
bool parse_imu_packet(const uint8_t* data, size_t size, ImuSample& out);
// Inverse of parse (float32 g and deg/s on the wire).
std::array<uint8_t, kImuPacketSize> encode_imu_packet(const ImuSample& s);

// ---- frames -----------------------------------------------------------------------------------
struct AssemblerStats {
  uint64_t packets = 0;            // lidar packets offered
  uint64_t packets_accepted = 0;
  uint64_t wrong_size = 0;
  uint64_t bad_measurement_id = 0; // columns
  uint64_t stale_packets = 0;      // packets of an already published frame
  uint64_t duplicate_columns = 0;
  uint64_t invalid_columns = 0;    // status bit clear
  uint64_t frames = 0;             // published
  uint64_t complete_frames = 0;
  uint64_t missing_columns = 0;    // sum over published frames
};

// Collects columns by frame_id into a Scan. A frame is published (appended to `out`) when all columns
// of the azimuth window are in, when a packet of another frame arrives, or on flush(). Columns never
// received (or with an invalid status) are marked column_valid = 0 and counted in missing_columns
// (status kIncomplete). Packets of the frame that was just published are dropped (stale), never merged
// into the next frame.
class FrameAssembler {
 public:
  explicit FrameAssembler(const SensorInfo& info);
  PacketError add_packet(const uint8_t* data, size_t size, std::vector<Scan>& out);
  void flush(std::vector<Scan>& out);
  const AssemblerStats& stats() const { return stats_; }
  const PacketFormat& format() const { return fmt_; }
  const SensorInfo& info() const { return info_; }
  // Publishes the frame in progress and forgets the last frame id (a replayed capture starting over, a
  // sensor restart): the next packets start a new frame whatever their id.
  void resync(std::vector<Scan>& out) {
    publish(out);
    have_last_ = false;
  }
  // Reuse a published Scan's buffers (optional; avoids allocation at 10 Hz).
  void recycle(Scan&& s) { spare_ = std::move(s); }

 private:
  static constexpr int kMaxColumnsPerPacket = 32;  // Ouster packets carry 16 columns
  void start(uint16_t frame_id);
  void publish(std::vector<Scan>& out);
  void scatter_column(const uint8_t* px, int m);  // one column down the range image
  SensorInfo info_;
  PacketFormat fmt_;
  LidarPacketView view_;
  Scan cur_, spare_;
  std::vector<uint8_t> seen_;
  bool active_ = false;
  bool have_last_ = false;
  uint16_t last_published_ = 0;
  int received_ = 0;
  int stale_run_ = 0;
  int64_t seq_ = 0;
  AssemblerStats stats_;
};

}  // namespace fploc::os1
