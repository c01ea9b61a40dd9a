// The low-data-rate profile RNG15_RFL8_NIR8 (4-byte pixels, range in 8 mm units): the real OS-1-128
// capture (fw 2.3, three 1024x10 frames) and an encode/decode round trip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fploc/core/xyz.h"
#include "fploc/os1/packet.h"
#include "fploc/os1/pcap.h"
#include "test_util.h"

using namespace fploc;
using namespace fploc::os1;
using fploc::os1::test::ouster_dir;

TEST(LowBandwidth, Os1128ThreeCompleteFrames) {
  FPLOC_REQUIRE_SHARED();
  const auto info = load_metadata(ouster_dir() + "/OS-1-128_v2.3.0_1024x10.json");
  ASSERT_EQ(info.profile, UdpProfile::kRng15Rfl8Nir8);
  PcapReader r;
  ASSERT_TRUE(r.open(ouster_dir() + "/OS-1-128_v2.3.0_1024x10_lb_n3.pcap")) << r.error();
  FrameAssembler fa(info);
  EXPECT_EQ(fa.format().lidar_packet_size(), 8448u);  // 32 + 16 * (12 + 128 * 4) + 32
  PacketClassifier cls{0, 0, fa.format().lidar_packet_size()};
  std::vector<Scan> frames;
  UdpDatagram d;
  int lidar = 0;
  while (r.next(d))
    if (cls.classify(d.dst_port, d.size) == PacketKind::kLidar) {
      ++lidar;
      EXPECT_EQ(fa.add_packet(d.data, d.size, frames), PacketError::kNone);
    }
  fa.flush(frames);
  EXPECT_EQ(lidar, 192);
  ASSERT_EQ(frames.size(), 3u);
  BeamIntrinsics beams = info.beams;
  for (const auto& s : frames) {
    EXPECT_EQ(s.height, 128);
    EXPECT_EQ(s.width, 1024);
    EXPECT_EQ(s.missing_columns, 0);
    size_t valid = 0, smooth = 0, pairs = 0;
    std::vector<uint32_t> rs;
    for (int b = 0; b < s.height; ++b) {
      // Destaggered neighbours see the same surface: most differ by a few percent at most. A wrong
      // pixel layout or range unit gives noise here.
      std::vector<uint32_t> row(s.width);
      for (int c = 0; c < s.width; ++c) row[destagger_column(beams, b, c, s.width)] = s.range(b, c);
      for (int c = 0; c < s.width; ++c) {
        const uint32_t a = row[c], n = row[(c + 1) % s.width];
        if (a) {
          ++valid;
          EXPECT_EQ(a % 8, 0u);
          rs.push_back(a);
        }
        if (a && n) {
          ++pairs;
          if (std::abs(double(a) - double(n)) < 0.05 * a + 30) ++smooth;
        }
      }
    }
    EXPECT_GT(valid, size_t(0.5 * s.height * s.width));
    EXPECT_GT(double(smooth) / pairs, 0.8);
    std::nth_element(rs.begin(), rs.begin() + rs.size() / 2, rs.end());
    EXPECT_GT(rs[rs.size() / 2], 500u);      // median range: metres, not noise
    EXPECT_LT(rs[rs.size() / 2], 60000u);
  }
  // Consecutive frames of a (slowly moving) sensor are almost the same picture.
  size_t same = 0, both = 0;
  for (size_t i = 0; i < frames[0].range_mm.size(); ++i) {
    const uint32_t a = frames[0].range_mm[i], b = frames[1].range_mm[i];
    if (a && b) {
      ++both;
      if (std::abs(double(a) - double(b)) < 0.05 * a + 30) ++same;
    }
  }
  EXPECT_GT(double(same) / both, 0.8);
}

TEST(LowBandwidth, EncodeDecodeRoundTrip) {
  SensorInfo info;
  info.profile = UdpProfile::kRng15Rfl8Nir8;
  info.pixels_per_column = 32;
  info.columns_per_packet = 16;
  info.columns_per_frame = 512;
  info.column_window_last = 511;
  info.beams.altitude_deg.assign(32, 0.0);
  info.beams.azimuth_deg.assign(32, 0.0);
  info.beams.pixel_shift_by_row.assign(32, 0);
  const PacketFormat f = PacketFormat::from(info);
  EXPECT_EQ(f.lidar_packet_size(), 32u + 16u * (12u + 32u * 4u) + 32u);
  Scan s;
  s.resize(32, 512);
  for (size_t i = 0; i < s.range_mm.size(); ++i) {
    s.range_mm[i] = uint32_t((i * 7919) % 40000) & ~7u;  // 8 mm steps survive exactly
    s.reflectivity[i] = uint8_t(i * 13);
  }
  s.range_mm[5] = 400000;  // beyond 15 bits * 8 mm: clipped
  for (int c = 0; c < 512; ++c) s.column_utime[c] = 1000 + c;
  std::vector<std::vector<uint8_t>> pkts;
  encode_frame(s, 7, f, pkts);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  for (const auto& p : pkts) EXPECT_EQ(fa.add_packet(p.data(), p.size(), out), PacketError::kNone);
  ASSERT_EQ(out.size(), 1u);
  for (size_t i = 0; i < s.range_mm.size(); ++i) {
    if (i == 5) {
      EXPECT_EQ(out[0].range_mm[i], 0x7FFFu * 8);
      continue;
    }
    ASSERT_EQ(out[0].range_mm[i], s.range_mm[i]) << i;
    ASSERT_EQ(out[0].reflectivity[i], s.reflectivity[i]) << i;
    ASSERT_EQ(out[0].signal[i], 0);
  }
  EXPECT_EQ(out[0].column_utime[17], 1017);
}
