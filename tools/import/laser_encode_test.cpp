// encode_laser_scan (one pass from the recording's bytes) gives the bytes of the previous import path:
// decode to rec::LaserScan, fill a laser_scan_t, laser_scan_t::encode. ROS 1 (little-endian) and
// big-endian CDR messages, with and without intensities, odd lengths (the vector loop's tail), NaN/inf
// bit patterns, an empty scan.
#include <gtest/gtest.h>

#include <fploc/laser_scan_t.hpp>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "laser_encode.h"

namespace {

using fploc::rec::Encoding;

struct Bytes {
  std::vector<uint8_t> b;
  bool be = false, cdr = false;
  void align(size_t a) {
    if (!cdr) return;
    while ((b.size() - 4) % a) b.push_back(0);
  }
  void u32(uint32_t v) {
    align(4);
    if (be) v = __builtin_bswap32(v);
    b.insert(b.end(), (uint8_t*)&v, (uint8_t*)&v + 4);
  }
  void raw32(uint32_t v) { u32(v); }
  void str(const std::string& s) {
    u32(uint32_t(s.size() + (cdr ? 1 : 0)));
    b.insert(b.end(), s.begin(), s.end());
    if (cdr) b.push_back(0);
  }
};

// A LaserScan message (ROS 1 or CDR of either byte order) with the given float bit patterns.
std::vector<uint8_t> message(Encoding e, bool big_endian, const std::string& frame, const std::vector<uint32_t>& ranges,
                             const std::vector<uint32_t>& intens) {
  Bytes m;
  m.cdr = e == Encoding::kCdr;
  if (m.cdr) m.b = {0, uint8_t(big_endian ? 0 : 1), 0, 0};
  m.be = big_endian;
  if (!m.cdr) m.u32(77);  // seq
  m.u32(1700000123);      // stamp sec
  m.u32(456789012);       // nsec
  m.str(frame);
  const float f[7] = {-2.3f, 2.3f, 0.0043f, 2.5e-5f, 0.025f, 0.02f, 30.0f};
  for (float x : f) {
    uint32_t u;
    std::memcpy(&u, &x, 4);
    m.raw32(u);
  }
  m.u32(uint32_t(ranges.size()));
  for (uint32_t u : ranges) m.raw32(u);
  m.u32(uint32_t(intens.size()));
  for (uint32_t u : intens) m.raw32(u);
  return m.b;
}

// The previous import path's bytes.
std::vector<uint8_t> reference(const std::vector<uint8_t>& msg, Encoding e) {
  fploc::rec::LaserScan l;
  std::string err;
  EXPECT_TRUE(fploc::rec::decode(msg.data(), msg.size(), e, l, &err)) << err;
  fploc::laser_scan_t ls;
  ls.utime = l.header.stamp_ns / 1000;
  ls.frame = l.header.frame_id;
  ls.angle_min = l.angle_min;
  ls.angle_increment = l.angle_increment;
  ls.time_increment = l.time_increment;
  ls.range_min = l.range_min;
  ls.range_max = l.range_max;
  ls.num_ranges = int32_t(l.ranges.size());
  ls.ranges = l.ranges;
  ls.num_intensities = int32_t(l.intensities.size());
  ls.intensities = l.intensities;
  std::vector<uint8_t> out(size_t(ls.getEncodedSize()));
  EXPECT_EQ(ls.encode(out.data(), 0, int(out.size())), int(out.size()));
  return out;
}

TEST(LaserEncode, SameBytesAsLaserScanTEncode) {
  std::mt19937 rng(3);
  int cases = 0;
  for (const auto& [e, be] : {std::pair{Encoding::kRos1, false}, {Encoding::kCdr, false}, {Encoding::kCdr, true}})
    for (size_t n : {size_t(0), size_t(1), size_t(7), size_t(31), size_t(1081), size_t(1440)})
      for (bool with_intensities : {false, true})
        for (const std::string frame : {"laser", "", "guardian/laser_horizontal_back_link_long_name"}) {
          std::vector<uint32_t> r(n), in(with_intensities ? n : 0);
          for (auto& u : r) u = rng();  // any bit pattern: NaNs, infinities, denormals included
          for (auto& u : in) u = rng();
          if (n > 3) r[1] = 0x7fc00001u, r[2] = 0xff800000u, r[3] = 0x80000000u;
          const auto msg = message(e, be, frame, r, in);
          fploc::rec::LaserScanView v;
          std::string err;
          ASSERT_TRUE(fploc::rec::decode(msg.data(), msg.size(), e, v, &err)) << err;
          EXPECT_EQ(v.big_endian, be);
          std::vector<uint8_t> ours(fploc::import::laser_scan_encoded_size(v) + 16, 0xAB);
          fploc::import::encode_laser_scan(v, ours.data());
          const auto ref = reference(msg, e);
          ASSERT_EQ(ours.size() - 16, ref.size());
          EXPECT_TRUE(std::equal(ref.begin(), ref.end(), ours.begin())) << "n " << n << " cdr " << int(e == Encoding::kCdr) << " be " << be;
          for (size_t k = ref.size(); k < ours.size(); ++k) ASSERT_EQ(ours[k], 0xAB) << "wrote past its size";
          ++cases;
        }
  EXPECT_EQ(cases, 3 * 6 * 2 * 3);
}

TEST(LaserEncode, ArraysPastTheEndAreAnError) {
  auto msg = message(Encoding::kRos1, false, "laser", std::vector<uint32_t>(100, 1), std::vector<uint32_t>(100, 2));
  msg.resize(msg.size() - 5);
  fploc::rec::LaserScanView v;
  std::string err;
  EXPECT_FALSE(fploc::rec::decode(msg.data(), msg.size(), Encoding::kRos1, v, &err));
  EXPECT_NE(err.find("intensities"), std::string::npos) << err;
  EXPECT_EQ(v.num_ranges + v.num_intensities, 0u);
}

}  // namespace
