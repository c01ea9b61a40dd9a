#include "fploc/os1/xsens.h"

#include <gtest/gtest.h>

#include <random>
#include <sstream>

using namespace fploc::os1;

namespace {
std::vector<uint8_t> hex(const std::string& s) {
  std::istringstream is(s);
  std::vector<uint8_t> out;
  std::string b;
  while (is >> b) out.push_back(uint8_t(std::stoul(b, nullptr, 16)));
  return out;
}
// A real MTData2 payload recorded from an MTi-300 with MT Manager's decoding (public "XSens Golden
// Packets" reference, example 3: counter, time, quaternion, acceleration, delta v, free acceleration,
// rate of turn, delta q, status word).
const char* kGolden =
    "10 20 02 8D 90 10 60 04 00 54 DB F1 20 10 10 3F 7F 89 11 BC 11 1D FA 3B A0 CE F0 BD 73 25 73 40 20 0C BD DC "
    "F9 D0 BE 3C 86 19 41 1D 0B 47 40 10 0C B9 8D B0 00 B9 F1 48 00 3C C9 04 30 40 30 0C BC B9 89 2E BB 09 8C 00 "
    "3C A7 08 00 80 20 0C BA 63 BC 01 BC 04 D6 3F BB 6D E3 FE 80 30 10 3F 80 00 01 B5 91 C0 00 B7 2A 08 00 B6 98 "
    "40 00 E0 20 04 00 40 00 03";
}  // namespace

TEST(Xsens, GoldenMtData2) {
  const auto p = hex(kGolden);
  ASSERT_EQ(p.size(), 117u);
  XsensSample s;
  ASSERT_TRUE(parse_mtdata2(p.data(), p.size(), s));
  EXPECT_TRUE(s.has_counter && s.has_time && s.has_accel && s.has_gyro);
  EXPECT_EQ(s.packet_counter, 36240);
  EXPECT_EQ(s.sample_time_fine, 5561329u);
  EXPECT_NEAR(s.accel[0], -0.10789835, 1e-7);
  EXPECT_NEAR(s.accel[1], -0.18410529, 1e-7);
  EXPECT_NEAR(s.accel[2], 9.81525326, 1e-6);
  EXPECT_NEAR(s.gyro[0], -0.00086874, 1e-8);
  EXPECT_NEAR(s.gyro[1], -0.00810772, 1e-8);
  EXPECT_NEAR(s.gyro[2], -0.00362992, 1e-8);
  // Truncated payloads are rejected, never read past the end.
  for (size_t n = 1; n < p.size(); ++n)
    if (n != 117) {
      XsensSample t;
      std::vector<uint8_t> cut(p.begin(), p.begin() + long(n));
      parse_mtdata2(cut.data(), cut.size(), t);
    }
  std::vector<uint8_t> bad(p.begin(), p.begin() + 40);
  EXPECT_FALSE(parse_mtdata2(bad.data(), bad.size(), s));
}

TEST(Xsens, FixedPointPrecisions) {
  // Acceleration as fp12.20 (XDI 0x4021) and rate of turn as fp16.32 (0x8022).
  std::vector<uint8_t> p = {0x40, 0x21, 12};
  for (int32_t v : {int32_t(1.5 * 1048576), int32_t(-2.25 * 1048576), int32_t(9.75 * 1048576)})
    for (int k = 3; k >= 0; --k) p.push_back(uint8_t(uint32_t(v) >> (8 * k)));
  p.insert(p.end(), {0x80, 0x22, 18});
  for (double v : {0.5, -1.25, 3.0}) {
    const int64_t raw = int64_t(v * 4294967296.0);
    const uint32_t frac = uint32_t(raw & 0xFFFFFFFF);
    const int16_t integer = int16_t(raw >> 32);
    for (int k = 3; k >= 0; --k) p.push_back(uint8_t(frac >> (8 * k)));
    p.push_back(uint8_t(uint16_t(integer) >> 8)), p.push_back(uint8_t(uint16_t(integer) & 0xFF));
  }
  XsensSample s;
  ASSERT_TRUE(parse_mtdata2(p.data(), p.size(), s));
  EXPECT_DOUBLE_EQ(s.accel[0], 1.5);
  EXPECT_DOUBLE_EQ(s.accel[1], -2.25);
  EXPECT_DOUBLE_EQ(s.accel[2], 9.75);
  EXPECT_DOUBLE_EQ(s.gyro[0], 0.5);
  EXPECT_DOUBLE_EQ(s.gyro[1], -1.25);
  EXPECT_DOUBLE_EQ(s.gyro[2], 3.0);
}

TEST(Xsens, StreamFramingResyncsOnGarbage) {
  const auto msg = xbus_message(kXbusMtData2, hex(kGolden));
  // Checksum of a known configuration message (GoToConfig: FA FF 30 00 D1).
  EXPECT_EQ(xbus_message(0x30, {}), (std::vector<uint8_t>{0xFA, 0xFF, 0x30, 0x00, 0xD1}));
  std::vector<uint8_t> stream;
  std::mt19937 rng(1);
  for (int i = 0; i < 20; ++i) {
    for (int k = 0; k < int(rng() % 30); ++k) stream.push_back(uint8_t(rng()));  // garbage, may hold 0xFA
    stream.insert(stream.end(), msg.begin(), msg.end());
  }
  auto corrupt = msg;
  corrupt[50] ^= 0x01;  // checksum error: dropped, counted
  stream.insert(stream.end(), corrupt.begin(), corrupt.end());
  stream.insert(stream.end(), msg.begin(), msg.end());
  XbusParser parser;
  int n = 0;
  for (size_t o = 0; o < stream.size(); o += 7)  // arbitrary chunking, as from a serial port
    parser.feed(stream.data() + o, std::min<size_t>(7, stream.size() - o), [&](const XsensSample& s) {
      EXPECT_EQ(s.packet_counter, 36240);
      ++n;
    });
  EXPECT_EQ(n, 21);
  EXPECT_GE(parser.stats().checksum_errors, 1u);
  EXPECT_EQ(parser.stats().samples, 21u);
}
