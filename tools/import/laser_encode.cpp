#include "laser_encode.h"

#include <fploc/laser_scan_t.hpp>

#include <cstring>

namespace fploc::import {
namespace {

uint8_t* put32(uint8_t* p, uint32_t v) {
  v = __builtin_bswap32(v);
  std::memcpy(p, &v, 4);
  return p + 4;
}
uint8_t* put64(uint8_t* p, uint64_t v) {
  v = __builtin_bswap64(v);
  std::memcpy(p, &v, 8);
  return p + 8;
}
uint8_t* put_float(uint8_t* p, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return put32(p, u);
}

// n little-endian 4-byte words -> big-endian (AVX2 where the CPU has it: 8 words per shuffle).
__attribute__((target_clones("avx2", "default"))) void swap_words(const uint8_t* src, uint8_t* dst, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    uint32_t v;
    std::memcpy(&v, src + 4 * i, 4);
    v = __builtin_bswap32(v);
    std::memcpy(dst + 4 * i, &v, 4);
  }
}

uint8_t* put_floats(uint8_t* p, const uint8_t* src, uint32_t n, bool big_endian) {
  p = put32(p, n);
  if (!n) return p;
  if (big_endian) std::memcpy(p, src, size_t(n) * 4);  // already LCM's byte order
  else swap_words(src, p, n);
  return p + size_t(n) * 4;
}

}  // namespace

namespace {
// The frame id as LCM encodes a std::string (strlen: up to a NUL inside it, if any).
size_t frame_len(const std::string& f) { return strnlen(f.c_str(), f.size()); }
}  // namespace

size_t laser_scan_encoded_size(const rec::LaserScanView& l) {
  return 8 + 8 + 4 + frame_len(l.header.frame_id) + 1 + 5 * 4 + 4 + size_t(l.num_ranges) * 4 + 4 + size_t(l.num_intensities) * 4;
}

void encode_laser_scan(const rec::LaserScanView& l, uint8_t* p) {
  p = put64(p, uint64_t(laser_scan_t::getHash()));
  p = put64(p, uint64_t(l.header.stamp_ns / 1000));
  const size_t fn = frame_len(l.header.frame_id);
  p = put32(p, uint32_t(fn + 1));
  std::memcpy(p, l.header.frame_id.c_str(), fn);
  p[fn] = 0;
  p += fn + 1;
  p = put_float(p, l.angle_min);
  p = put_float(p, l.angle_increment);
  p = put_float(p, l.time_increment);
  p = put_float(p, l.range_min);
  p = put_float(p, l.range_max);
  p = put_floats(p, l.ranges, l.num_ranges, l.big_endian);
  put_floats(p, l.intensities, l.num_intensities, l.big_endian);
}

}  // namespace fploc::import
