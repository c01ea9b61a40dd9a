#include "fploc/os1/xsens.h"

#include <cmath>
#include <cstring>

namespace fploc::os1 {
namespace {

uint16_t be16(const uint8_t* p) { return uint16_t((p[0] << 8) | p[1]); }
uint32_t be32(const uint8_t* p) { return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3]; }

// Reads 3 values of the XDI's precision; false on a size mismatch or a non-finite value.
bool vec3(uint16_t xdi, const uint8_t* p, size_t n, std::array<double, 3>& out) {
  const int prec = xdi & 0x3;
  static const size_t kSize[] = {4, 4, 6, 8};
  if (n != 3 * kSize[prec]) return false;
  for (int i = 0; i < 3; ++i) {
    const uint8_t* q = p + i * kSize[prec];
    double v = 0;
    switch (prec) {
      case 0: {
        const uint32_t u = be32(q);
        float f;
        std::memcpy(&f, &u, 4);
        v = f;
        break;
      }
      case 1: v = double(int32_t(be32(q))) / 1048576.0; break;  // fp12.20
      case 2: {                                                 // fp16.32: 4 B fraction, 2 B integer
        const int64_t raw = (int64_t(int16_t(be16(q + 4))) * 4294967296LL) + int64_t(be32(q));
        v = double(raw) / 4294967296.0;
        break;
      }
      case 3: {
        const uint64_t u = (uint64_t(be32(q)) << 32) | be32(q + 4);
        std::memcpy(&v, &u, 8);
        break;
      }
    }
    if (!std::isfinite(v)) return false;
    out[i] = v;
  }
  return true;
}

}  // namespace

bool parse_mtdata2(const uint8_t* p, size_t size, XsensSample& s) {
  s = XsensSample{};
  size_t o = 0;
  while (o < size) {
    if (size - o < 3) return false;
    const uint16_t xdi = be16(p + o);
    const size_t n = p[o + 2];
    o += 3;
    if (n > size - o) return false;
    const uint8_t* d = p + o;
    switch (xdi & 0xFFF0) {
      case 0x1020:
        if (n != 2) return false;
        s.packet_counter = be16(d), s.has_counter = true;
        break;
      case 0x1060:
        if (n != 4) return false;
        s.sample_time_fine = be32(d), s.has_time = true;
        break;
      case 0x4020:
        if (!vec3(xdi, d, n, s.accel)) return false;
        s.has_accel = true;
        break;
      case 0x8020:
        if (!vec3(xdi, d, n, s.gyro)) return false;
        s.has_gyro = true;
        break;
      default:
        break;  // other outputs (orientation, magnetometer, status, ...) are skipped
    }
    o += n;
  }
  return true;
}

std::vector<uint8_t> xbus_message(uint8_t mid, const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> m{0xFA, 0xFF, mid};
  if (payload.size() < 0xFF) {
    m.push_back(uint8_t(payload.size()));
  } else {
    m.push_back(0xFF);
    m.push_back(uint8_t(payload.size() >> 8));
    m.push_back(uint8_t(payload.size() & 0xFF));
  }
  m.insert(m.end(), payload.begin(), payload.end());
  uint8_t sum = 0;
  for (size_t i = 1; i < m.size(); ++i) sum = uint8_t(sum + m[i]);
  m.push_back(uint8_t(-sum));
  return m;
}

void XbusParser::feed(const uint8_t* data, size_t size, const std::function<void(const XsensSample&)>& fn) {
  buf_.insert(buf_.end(), data, data + size);
  size_t o = 0;
  for (;;) {
    while (o < buf_.size() && buf_[o] != 0xFA) ++o, ++stats_.skipped_bytes;
    if (buf_.size() - o < 5) break;
    size_t hdr = 4, len = buf_[o + 3];
    if (len == 0xFF) {
      if (buf_.size() - o < 7) break;
      hdr = 6, len = be16(&buf_[o + 4]);
    }
    if (buf_[o + 1] != 0xFF) {  // not a bus-master message: a stray 0xFA in the data
      ++o, ++stats_.skipped_bytes;
      continue;
    }
    if (buf_.size() - o < hdr + len + 1) break;  // wait for the rest
    uint8_t sum = 0;
    for (size_t i = o + 1; i < o + hdr + len + 1; ++i) sum = uint8_t(sum + buf_[i]);
    if (sum != 0) {
      ++stats_.checksum_errors;
      ++o, ++stats_.skipped_bytes;  // resynchronise on the next preamble
      continue;
    }
    ++stats_.messages;
    const uint8_t mid = buf_[o + 2];
    if (mid == kXbusMtData2) {
      XsensSample s;
      if (parse_mtdata2(&buf_[o + hdr], len, s)) {
        ++stats_.samples;
        fn(s);
      } else {
        ++stats_.bad_payloads;
      }
    } else {
      ++stats_.other_messages;
    }
    o += hdr + len + 1;
  }
  buf_.erase(buf_.begin(), buf_.begin() + long(o));
  if (buf_.size() > (1u << 20)) {  // never grow without bound on a stream without preambles
    stats_.skipped_bytes += buf_.size();
    buf_.clear();
  }
}

}  // namespace fploc::os1
