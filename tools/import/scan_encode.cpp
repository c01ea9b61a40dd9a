#include "scan_encode.h"

#include <fploc/scan_t.hpp>

#include <algorithm>
#include <cstring>

namespace fploc::import {

namespace {

// LCM encodes every number big-endian.
struct Put {
  uint8_t* p;
  void u8(uint8_t v) { *p++ = v; }
  void be16(uint16_t v) {
    v = __builtin_bswap16(v);
    std::memcpy(p, &v, 2);
    p += 2;
  }
  void be32(uint32_t v) {
    v = __builtin_bswap32(v);
    std::memcpy(p, &v, 4);
    p += 4;
  }
  void be64(uint64_t v) {
    v = __builtin_bswap64(v);
    std::memcpy(p, &v, 8);
    p += 8;
  }
  void f32(float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    be32(v);
  }
  void f64(double d) {
    uint64_t v;
    std::memcpy(&v, &d, 8);
    be64(v);
  }
};

}  // namespace

size_t encoded_scan_size(const Scan& s) {
  const size_t h = size_t(std::max(0, s.height)), w = size_t(std::max(0, s.width));
  const size_t n = h * w;
  return 8 + 8 + 8 + 4 + 4 + s.sensor.size() + 1 + 2 + 2 + 4 + n * (4 + 2 + 1) + w * (8 + 2 + 1) + h * (4 + 4 + 2) + 4 +
         16 * 8 + 4 + 1;
}

void encode_scan(const Scan& s, std::vector<uint8_t>& out) {
  out.resize(encoded_scan_size(s));
  encode_scan(s, out.data());
}

void encode_scan(const Scan& s, uint8_t* out) {
  const size_t h = size_t(std::max(0, s.height)), w = size_t(std::max(0, s.width));
  const size_t n = h * w;
  Put o{out};
  o.be64(uint64_t(scan_t::getHash()));
  o.be64(uint64_t(s.utime));
  o.be64(uint64_t(s.seq));
  o.be32(uint32_t(s.frame_id));
  o.be32(uint32_t(s.sensor.size() + 1));
  std::memcpy(o.p, s.sensor.data(), s.sensor.size());
  o.p += s.sensor.size();
  o.u8(0);
  o.be16(uint16_t(int16_t(s.height)));
  o.be16(uint16_t(int16_t(s.width)));
  o.be32(uint32_t(n));
  // Pixels (to_msg: range as is, signal saturated to int16, missing arrays as zeros).
  {
    const size_t k = std::min(n, s.range_mm.size());
    uint8_t* p = o.p;
    const uint32_t* r = s.range_mm.data();
    for (size_t i = 0; i < k; ++i) {  // shifts (not bswap): SSE2 vectorizes them
      const uint32_t x = r[i];
      const uint32_t v = (x >> 24) | ((x >> 8) & 0xFF00u) | ((x << 8) & 0xFF0000u) | (x << 24);
      std::memcpy(p + 4 * i, &v, 4);
    }
    std::memset(p + 4 * k, 0, 4 * (n - k));
    o.p += 4 * n;
  }
  {
    const size_t k = std::min(n, s.signal.size());
    uint8_t* p = o.p;
    const uint16_t* g = s.signal.data();
    for (size_t i = 0; i < k; ++i) {
      const uint16_t x = std::min<uint16_t>(g[i], 32767);
      const uint16_t v = uint16_t((x >> 8) | (x << 8));
      std::memcpy(p + 2 * i, &v, 2);
    }
    std::memset(p + 2 * k, 0, 2 * (n - k));
    o.p += 2 * n;
  }
  {
    const size_t k = std::min(n, s.reflectivity.size());
    if (k) std::memcpy(o.p, s.reflectivity.data(), k);
    std::memset(o.p + k, 0, n - k);
    o.p += n;
  }
  // Columns (to_msg: missing times are utime, missing ids their index, missing validity true).
  for (size_t c = 0; c < w; ++c) o.be64(uint64_t(c < s.column_utime.size() ? s.column_utime[c] : s.utime));
  for (size_t c = 0; c < w; ++c) o.be16(uint16_t(c < s.measurement_id.size() ? int16_t(s.measurement_id[c]) : int16_t(c)));
  for (size_t c = 0; c < w; ++c) o.u8(c < s.column_valid.size() ? s.column_valid[c] != 0 : 1);
  const auto& b = s.beams;
  for (size_t u = 0; u < h; ++u) o.f32(u < b.altitude_deg.size() ? float(b.altitude_deg[u]) : 0.f);
  for (size_t u = 0; u < h; ++u) o.f32(u < b.azimuth_deg.size() ? float(b.azimuth_deg[u]) : 0.f);
  for (size_t u = 0; u < h; ++u) o.be16(uint16_t(u < b.pixel_shift_by_row.size() ? int16_t(b.pixel_shift_by_row[u]) : 0));
  o.f32(float(b.beam_offset_mm));
  for (double d : b.lidar_to_sensor) o.f64(d);
  o.be32(uint32_t(s.missing_columns));
  o.u8(uint8_t(int8_t(s.status)));
}

}  // namespace fploc::import
