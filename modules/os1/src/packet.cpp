#include "fploc/os1/packet.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace fploc::os1 {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "wire format is little-endian; add byte swaps for BE hosts");

template <class T>
inline T rd(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <class T>
inline void wr(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

}  // namespace

const char* to_string(PacketError e) {
  switch (e) {
    case PacketError::kNone: return "ok";
    case PacketError::kWrongSize: return "wrong packet size";
    case PacketError::kBadMeasurementId: return "measurement id out of range";
    case PacketError::kStaleFrame: return "packet of an already published frame";
    case PacketError::kDuplicateColumn: return "duplicate column";
    case PacketError::kInvalidColumns: return "column status invalid";
  }
  return "?";
}

PacketFormat PacketFormat::from(const SensorInfo& info) {
  PacketFormat f;
  f.profile = info.profile;
  f.pixels_per_column = info.pixels_per_column;
  f.columns_per_packet = info.columns_per_packet;
  f.columns_per_frame = info.columns_per_frame;
  return f;
}

// ---- view -------------------------------------------------------------------------------------
bool LidarPacketView::reset(const PacketFormat& f, const uint8_t* data, size_t size, PacketError* err) {
  f_ = f;
  if (data == nullptr || size != f.lidar_packet_size() || f.columns_per_packet <= 0 || f.pixels_per_column <= 0) {
    data_ = nullptr;
    if (err) *err = PacketError::kWrongSize;
    return false;
  }
  data_ = data;
  if (err) *err = PacketError::kNone;
  return true;
}

ColumnHeader LidarPacketView::column(int c) const {
  const uint8_t* p = data_ + f_.packet_header_size() + size_t(c) * f_.column_size();
  ColumnHeader h;
  h.timestamp_ns = rd<uint64_t>(p);
  h.measurement_id = rd<uint16_t>(p + 8);
  if (f_.profile == UdpProfile::kLegacy) {
    h.frame_id = rd<uint16_t>(p + 10);
    h.encoder_count = rd<uint32_t>(p + 12);
    h.status = rd<uint32_t>(p + f_.column_size() - 4);
  } else {
    h.frame_id = rd<uint16_t>(data_ + 2);
    h.status = rd<uint16_t>(p + 10);
  }
  return h;
}

uint16_t LidarPacketView::packet_frame_id() const {
  if (f_.profile == UdpProfile::kLegacy) return rd<uint16_t>(data_ + 10);
  return rd<uint16_t>(data_ + 2);
}

uint32_t LidarPacketView::range_mm(int c, int b) const {
  if (f_.profile == UdpProfile::kRng15Rfl8Nir8) return uint32_t(rd<uint16_t>(pixel(c, b)) & 0x7FFFu) << 3;
  const uint32_t w = rd<uint32_t>(pixel(c, b));
  return f_.profile == UdpProfile::kLegacy ? (w & 0x000FFFFFu) : (w & 0x0007FFFFu);
}
uint16_t LidarPacketView::reflectivity(int c, int b) const {
  if (f_.profile == UdpProfile::kRng15Rfl8Nir8) return pixel(c, b)[2];
  return f_.profile == UdpProfile::kLegacy ? rd<uint16_t>(pixel(c, b) + 4) : uint16_t(pixel(c, b)[4]);
}
uint16_t LidarPacketView::signal(int c, int b) const {
  return f_.profile == UdpProfile::kRng15Rfl8Nir8 ? 0 : rd<uint16_t>(pixel(c, b) + 6);  // LB: no signal field
}
uint16_t LidarPacketView::near_ir(int c, int b) const {
  // LB: 8-bit NIR scaled by 16, as the Ouster SDK reads it
  return f_.profile == UdpProfile::kRng15Rfl8Nir8 ? uint16_t(pixel(c, b)[3] << 4) : rd<uint16_t>(pixel(c, b) + 8);
}

// ---- encode -----------------------------------------------------------------------------------
void encode_lidar_packet(const Scan& scan, int first_column, uint16_t frame_id, const PacketFormat& f,
                         std::vector<uint8_t>& out) {
  if (scan.height != f.pixels_per_column || scan.width != f.columns_per_frame)
    throw std::invalid_argument("encode_lidar_packet: scan is " + std::to_string(scan.height) + "x" +
                                std::to_string(scan.width) + ", format expects " +
                                std::to_string(f.pixels_per_column) + "x" + std::to_string(f.columns_per_frame));
  if (scan.range_mm.size() != size_t(scan.height) * scan.width)
    throw std::invalid_argument("encode_lidar_packet: range_mm size does not match height*width");
  out.assign(f.lidar_packet_size(), 0);
  const bool legacy = f.profile == UdpProfile::kLegacy;
  const uint32_t range_mask = legacy ? 0x000FFFFFu : 0x0007FFFFu;
  const size_t W = size_t(scan.width);
  const bool has_sig = scan.signal.size() == scan.range_mm.size();
  const bool has_refl = scan.reflectivity.size() == scan.range_mm.size();
  if (!legacy) {
    wr<uint16_t>(out.data(), 1);  // packet_type: lidar
    wr<uint16_t>(out.data() + 2, frame_id);
  }
  for (int k = 0; k < f.columns_per_packet; ++k) {
    const int m = first_column + k;
    uint8_t* p = out.data() + f.packet_header_size() + size_t(k) * f.column_size();
    if (m < 0 || m >= scan.width) continue;  // past the end: an all-zero (invalid) column
    const bool valid = scan.column_valid.size() == W ? scan.column_valid[m] != 0 : true;
    const int64_t us = scan.column_utime.size() == W ? scan.column_utime[m] : scan.utime;
    wr<uint64_t>(p, uint64_t(us) * 1000u);
    wr<uint16_t>(p + 8, uint16_t(m));
    if (legacy) {
      wr<uint16_t>(p + 10, frame_id);
      wr<uint32_t>(p + 12, uint32_t(uint64_t(m) * kEncoderTicksPerRev / W));
      wr<uint32_t>(p + f.column_size() - 4, valid ? 0xFFFFFFFFu : 0u);
    } else {
      wr<uint16_t>(p + 10, valid ? 1 : 0);
    }
    if (!valid) continue;
    uint8_t* px = p + f.column_header_size();
    if (f.profile == UdpProfile::kRng15Rfl8Nir8) {
      for (int b = 0; b < scan.height; ++b, px += 4) {
        const size_t i = size_t(b) * W + m;
        wr<uint16_t>(px, uint16_t(std::min<uint32_t>((scan.range_mm[i] + 4) >> 3, 0x7FFFu)));
        if (has_refl) px[2] = scan.reflectivity[i];
      }
      continue;
    }
    for (int b = 0; b < scan.height; ++b, px += 12) {
      const size_t i = size_t(b) * W + m;
      wr<uint32_t>(px, std::min(scan.range_mm[i], range_mask));
      if (has_refl) {
        if (legacy) wr<uint16_t>(px + 4, scan.reflectivity[i]);
        else px[4] = scan.reflectivity[i];
      }
      if (has_sig) wr<uint16_t>(px + 6, scan.signal[i]);
    }
  }
}

void encode_frame(const Scan& scan, uint16_t frame_id, const PacketFormat& f, std::vector<std::vector<uint8_t>>& out) {
  const int n = (f.columns_per_frame + f.columns_per_packet - 1) / f.columns_per_packet;
  out.resize(size_t(n));
  for (int i = 0; i < n; ++i) encode_lidar_packet(scan, i * f.columns_per_packet, frame_id, f, out[i]);
}

// ---- IMU --------------------------------------------------------------------------------------
bool parse_imu_packet(const uint8_t* d, size_t size, ImuSample& s) {
  if (d == nullptr || size != kImuPacketSize) return false;
  s.sys_ts_ns = rd<uint64_t>(d);
  s.accel_ts_ns = rd<uint64_t>(d + 8);
  s.gyro_ts_ns = rd<uint64_t>(d + 16);
  for (int i = 0; i < 3; ++i) {
    const float a = rd<float>(d + 24 + 4 * i);
    const float g = rd<float>(d + 36 + 4 * i);
    if (!std::isfinite(a) || !std::isfinite(g)) return false;
    s.accel_mps2[i] = double(a) * kStandardGravity;
    s.gyro_radps[i] = double(g) * M_PI / 180.0;
  }
  return true;
}

std::array<uint8_t, kImuPacketSize> encode_imu_packet(const ImuSample& s) {
  std::array<uint8_t, kImuPacketSize> b{};
  wr<uint64_t>(b.data(), s.sys_ts_ns);
  wr<uint64_t>(b.data() + 8, s.accel_ts_ns);
  wr<uint64_t>(b.data() + 16, s.gyro_ts_ns);
  for (int i = 0; i < 3; ++i) {
    wr<float>(b.data() + 24 + 4 * i, float(s.accel_mps2[i] / kStandardGravity));
    wr<float>(b.data() + 36 + 4 * i, float(s.gyro_radps[i] * 180.0 / M_PI));
  }
  return b;
}

// ---- frames -----------------------------------------------------------------------------------
FrameAssembler::FrameAssembler(const SensorInfo& info) : info_(info), fmt_(PacketFormat::from(info)) {}

void FrameAssembler::start(uint16_t frame_id) {
  if (spare_.range_mm.capacity() >= size_t(fmt_.pixels_per_column) * fmt_.columns_per_frame) cur_ = std::move(spare_);
  spare_ = Scan{};
  cur_.resize(fmt_.pixels_per_column, fmt_.columns_per_frame);
  cur_.column_valid.assign(size_t(fmt_.columns_per_frame), 0);
  cur_.frame_id = frame_id;
  cur_.sensor = info_.sensor_name();
  cur_.beams = info_.beams;
  cur_.missing_columns = 0;
  cur_.status = ScanStatus::kOk;
  cur_.utime = 0;
  seen_.assign(size_t(fmt_.columns_per_frame), 0);
  received_ = 0;
  active_ = true;
}

void FrameAssembler::publish(std::vector<Scan>& out) {
  if (!active_) return;
  int missing = 0;
  bool have_t = false;
  for (int m = 0; m < cur_.width; ++m) {
    if (!info_.in_window(m)) continue;
    if (!cur_.column_valid[m]) {
      ++missing;
    } else if (!have_t) {
      cur_.utime = cur_.column_utime[m];
      have_t = true;
    }
  }
  cur_.missing_columns = missing;
  cur_.status = missing ? ScanStatus::kIncomplete : ScanStatus::kOk;
  cur_.seq = seq_++;
  ++stats_.frames;
  if (!missing) ++stats_.complete_frames;
  stats_.missing_columns += uint64_t(missing);
  last_published_ = uint16_t(cur_.frame_id);
  have_last_ = true;
  active_ = false;
  out.push_back(std::move(cur_));
  cur_ = Scan{};
}

void FrameAssembler::flush(std::vector<Scan>& out) { publish(out); }

void FrameAssembler::scatter_column(const uint8_t* px, int m) {
  const size_t W = size_t(fmt_.columns_per_frame);
  uint32_t* rng = cur_.range_mm.data() + m;
  uint16_t* sig = cur_.signal.data() + m;
  uint8_t* refl = cur_.reflectivity.data() + m;
  if (fmt_.profile == UdpProfile::kRng15Rfl8Nir8) {
    for (int b = 0; b < fmt_.pixels_per_column; ++b, px += 4) {
      const size_t o = size_t(b) * W;
      rng[o] = uint32_t(rd<uint16_t>(px) & 0x7FFFu) << 3;
      sig[o] = 0;
      refl[o] = px[2];
    }
    return;
  }
  const uint32_t mask = fmt_.profile == UdpProfile::kLegacy ? 0x000FFFFFu : 0x0007FFFFu;
  for (int b = 0; b < fmt_.pixels_per_column; ++b, px += 12) {
    const size_t o = size_t(b) * W;
    rng[o] = rd<uint32_t>(px) & mask;
    sig[o] = rd<uint16_t>(px + 6);
    refl[o] = px[4];
  }
}

PacketError FrameAssembler::add_packet(const uint8_t* data, size_t size, std::vector<Scan>& out) {
  ++stats_.packets;
  PacketError err;
  if (!view_.reset(fmt_, data, size, &err)) {
    ++stats_.wrong_size;
    return err;
  }
  const uint16_t fid = view_.packet_frame_id();
  // Frames behind the current/last one (mod 2^16) are late packets: drop, never merge. A long run of
  // them means the sensor restarted its counter: resynchronise.
  const bool behind = active_ ? int16_t(uint16_t(fid - uint16_t(cur_.frame_id))) < 0
                              : (have_last_ && int16_t(uint16_t(fid - last_published_)) <= 0);
  if (behind) {
    const int per_frame = fmt_.columns_per_frame / std::max(1, fmt_.columns_per_packet);
    if (++stale_run_ <= 2 * per_frame) {
      ++stats_.stale_packets;
      return PacketError::kStaleFrame;
    }
    publish(out);
    have_last_ = false;
  }
  stale_run_ = 0;
  if (active_ && fid != uint16_t(cur_.frame_id)) publish(out);
  if (!active_) start(fid);
  ++stats_.packets_accepted;

  PacketError result = PacketError::kNone;
  const size_t W = size_t(fmt_.columns_per_frame);
  const bool legacy = fmt_.profile == UdpProfile::kLegacy;
  // Headers first, then the pixels row by row: the range image is row-major, so writing each row's
  // run of this packet's columns is sequential instead of one cache line per pixel (the scatter down
  // the columns was most of an import's CPU time).
  // The packet is read once, mostly from memory (a recording's page cache): ask for all of its lines
  // now so the misses overlap instead of stalling the pixel loops one by one.
  for (size_t off = 0; off < size; off += 64) __builtin_prefetch(data + off);
  int ms[kMaxColumnsPerPacket];
  const uint8_t* pxs[kMaxColumnsPerPacket];
  int n = 0;
  for (int c = 0; c < fmt_.columns_per_packet; ++c) {
    const ColumnHeader h = view_.column(c);
    if (h.measurement_id >= W || (legacy && h.frame_id != fid)) {
      ++stats_.bad_measurement_id;
      result = PacketError::kBadMeasurementId;
      continue;
    }
    const int m = h.measurement_id;
    if (seen_[m]) {
      ++stats_.duplicate_columns;
      if (result == PacketError::kNone) result = PacketError::kDuplicateColumn;
      continue;
    }
    seen_[m] = 1;
    if (info_.in_window(m)) ++received_;
    if (!h.valid()) {
      ++stats_.invalid_columns;
      if (result == PacketError::kNone) result = PacketError::kInvalidColumns;
      continue;
    }
    cur_.column_utime[m] = int64_t(h.timestamp_ns / 1000u);
    cur_.column_valid[m] = 1;
    if (n < kMaxColumnsPerPacket) {
      ms[n] = m;
      pxs[n++] = view_.pixel(c, 0);
    } else {
      scatter_column(view_.pixel(c, 0), m);  // (no format has more columns per packet)
    }
  }
  const int H = fmt_.pixels_per_column;
  if (fmt_.profile == UdpProfile::kRng15Rfl8Nir8) {
    for (int b = 0; b < H; ++b) {
      const size_t o = size_t(b) * W;
      uint32_t* rng = cur_.range_mm.data() + o;
      uint16_t* sig = cur_.signal.data() + o;
      uint8_t* refl = cur_.reflectivity.data() + o;
      const size_t po = size_t(b) * 4;
      for (int i = 0; i < n; ++i) {
        const uint8_t* px = pxs[i] + po;
        const int m = ms[i];
        rng[m] = uint32_t(rd<uint16_t>(px) & 0x7FFFu) << 3;  // 8 mm units
        sig[m] = 0;                                           // the profile carries no signal
        refl[m] = px[2];
      }
    }
  } else {
    const uint32_t mask = legacy ? 0x000FFFFFu : 0x0007FFFFu;
    for (int b = 0; b < H; ++b) {
      const size_t o = size_t(b) * W;
      uint32_t* rng = cur_.range_mm.data() + o;
      uint16_t* sig = cur_.signal.data() + o;
      uint8_t* refl = cur_.reflectivity.data() + o;
      const size_t po = size_t(b) * 12;
      for (int i = 0; i < n; ++i) {
        const uint8_t* px = pxs[i] + po;
        const int m = ms[i];
        rng[m] = rd<uint32_t>(px) & mask;
        sig[m] = rd<uint16_t>(px + 6);
        refl[m] = px[4];  // legacy: low 8 bits of the 16-bit field, as the Ouster SDK reads it
      }
    }
  }
  if (received_ >= info_.window_columns()) publish(out);
  return result;
}

}  // namespace fploc::os1
