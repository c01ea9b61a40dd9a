#include "fploc/os1/pcap.h"

#include <gtest/gtest.h>

#include "fploc/os1/packet.h"
#include "test_util.h"

using namespace fploc;
using namespace fploc::os1;
using fploc::os1::test::ouster_dir;

TEST(Pcap, Os164OneFrameElevenImu) {
  FPLOC_REQUIRE_SHARED();
  auto info = load_metadata(ouster_dir() + "/OS-1-64_sensor_config_reduced.json");
  PcapReader r;
  ASSERT_TRUE(r.open(ouster_dir() + "/OS-1-64_1024x10_fw20.pcap")) << r.error();
  FrameAssembler fa(info);
  PacketClassifier cls{0, 0, fa.format().lidar_packet_size()};
  std::vector<Scan> frames;
  int imu = 0, lidar = 0;
  double az = 0;
  UdpDatagram d;
  while (r.next(d)) {
    auto k = cls.classify(d.dst_port, d.size);
    if (k == PacketKind::kLidar) {
      ++lidar;
      fa.add_packet(d.data, d.size, frames);
    } else if (k == PacketKind::kImu) {
      ImuSample s;
      EXPECT_TRUE(parse_imu_packet(d.data, d.size, s));
      EXPECT_NEAR(s.accel_mps2[2], 9.77, 0.6);
      az += s.accel_mps2[2];
      ++imu;
    }
  }
  fa.flush(frames);
  EXPECT_TRUE(r.error().empty()) << r.error();
  EXPECT_EQ(lidar, 64);
  EXPECT_EQ(imu, 11);
  EXPECT_NEAR(az / imu, 0.996 * kStandardGravity, 0.1);  // notes: mean ~0.996 g
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].frame_id, 189);
  EXPECT_EQ(frames[0].missing_columns, 0);
  EXPECT_EQ(frames[0].height, 64);
  EXPECT_EQ(frames[0].width, 1024);
}

TEST(Pcap, SamePortsNeedsReassembly) {
  FPLOC_REQUIRE_SHARED();
  PcapReader r;
  ASSERT_TRUE(r.open(ouster_dir() + "/same_ports_legacy.pcap")) << r.error();
  UdpDatagram d;
  size_t big = 0;
  while (r.next(d))
    if (d.size > 1500) ++big;
  EXPECT_TRUE(r.error().empty()) << r.error();
  EXPECT_GT(r.stats().fragments, 0u);
  EXPECT_GT(r.stats().reassembled, 0u);
  EXPECT_EQ(big, r.stats().reassembled);
}

TEST(Pcap, CorruptFileReportsError) {
  FPLOC_REQUIRE_SHARED();
  std::FILE* f = std::fopen((ouster_dir() + "/OS-1-64_1024x10_fw20.pcap").c_str(), "rb");
  ASSERT_NE(f, nullptr);
  std::vector<uint8_t> buf(811814);
  buf.resize(std::fread(buf.data(), 1, buf.size(), f));
  std::fclose(f);
  // Truncated in the middle of a record.
  std::vector<uint8_t> cut(buf.begin(), buf.begin() + 100000);
  PcapReader r;
  ASSERT_TRUE(r.open_memory(cut.data(), cut.size()));
  UdpDatagram d;
  int n = 0;
  while (r.next(d)) ++n;
  EXPECT_GT(n, 0);
  EXPECT_FALSE(r.error().empty());
  // Bad magic.
  std::vector<uint8_t> bad = buf;
  bad[0] ^= 0xFF;
  EXPECT_FALSE(r.open_memory(bad.data(), bad.size()));
  EXPECT_FALSE(r.error().empty());
  EXPECT_FALSE(r.open("/nonexistent.pcap"));
  // Garbage record lengths: a huge caplen in the first record header.
  std::vector<uint8_t> huge = buf;
  huge[24 + 8] = 0xFF, huge[24 + 9] = 0xFF, huge[24 + 10] = 0xFF, huge[24 + 11] = 0x7F;
  ASSERT_TRUE(r.open_memory(huge.data(), huge.size()));
  while (r.next(d)) {
  }
  EXPECT_FALSE(r.error().empty());
}

TEST(Pcap, ReassemblerOutOfOrderAndOverflow) {
  // One UDP datagram of 3000 payload bytes split into 3 fragments, fed last-first.
  std::vector<uint8_t> udp(8 + 3000);
  udp[0] = 0x1D, udp[1] = 0x4E;  // 7502
  udp[2] = 0x1D, udp[3] = 0x4E;
  udp[4] = uint8_t((udp.size() >> 8) & 0xFF), udp[5] = uint8_t(udp.size() & 0xFF);
  for (size_t i = 8; i < udp.size(); ++i) udp[i] = uint8_t(i * 7);
  auto frag = [&](size_t off, size_t len, bool more) {
    std::vector<uint8_t> ip(20 + len);
    ip[0] = 0x45;
    ip[2] = uint8_t((ip.size() >> 8) & 0xFF), ip[3] = uint8_t(ip.size() & 0xFF);
    ip[4] = 0x12, ip[5] = 0x34;
    const uint16_t fo = uint16_t((off / 8) | (more ? 0x2000 : 0));
    ip[6] = uint8_t(fo >> 8), ip[7] = uint8_t(fo & 0xFF);
    ip[9] = 17;
    ip[12] = 10, ip[15] = 1, ip[16] = 10, ip[19] = 2;
    std::copy(udp.begin() + long(off), udp.begin() + long(off + len), ip.begin() + 20);
    return ip;
  };
  auto f1 = frag(0, 1480, true), f2 = frag(1480, 1480, true), f3 = frag(2960, udp.size() - 2960, false);
  Ipv4Reassembler ra;
  std::vector<uint8_t> scratch;
  UdpDatagram d;
  PcapStats st;
  EXPECT_FALSE(decode_frame(101, f3.data(), f3.size(), f3.size(), 0, ra, scratch, d, st));
  EXPECT_FALSE(decode_frame(101, f1.data(), f1.size(), f1.size(), 0, ra, scratch, d, st));
  ASSERT_TRUE(decode_frame(101, f2.data(), f2.size(), f2.size(), 0, ra, scratch, d, st));
  EXPECT_EQ(d.size, 3000u);
  EXPECT_EQ(d.dst_port, 7502);
  EXPECT_TRUE(std::equal(d.data, d.data + d.size, udp.begin() + 8));
  EXPECT_EQ(st.reassembled, 1u);
  // A lone fragment expires after 10 s of capture time and is counted.
  EXPECT_FALSE(decode_frame(101, f1.data(), f1.size(), f1.size(), 0, ra, scratch, d, st));
  EXPECT_FALSE(decode_frame(101, f3.data(), f3.size(), f3.size(), 20'000'000, ra, scratch, d, st));
  EXPECT_EQ(st.fragments_dropped, 1u);
  // Truncated capture.
  EXPECT_FALSE(decode_frame(101, f1.data(), 30, f1.size(), 0, ra, scratch, d, st));
  EXPECT_EQ(st.truncated_records, 1u);
}

TEST(Pcap, Classifier) {
  PacketClassifier same{7502, 7502, 12608};
  EXPECT_EQ(same.classify(7502, 12608), PacketKind::kLidar);
  EXPECT_EQ(same.classify(7502, 48), PacketKind::kImu);
  EXPECT_EQ(same.classify(7502, 100), PacketKind::kOther);
  PacketClassifier split{7502, 7503, 12608};
  EXPECT_EQ(split.classify(7502, 100), PacketKind::kLidar);  // wrong size: the parser counts it
  EXPECT_EQ(split.classify(7503, 47), PacketKind::kImu);
  EXPECT_EQ(split.classify(9999, 12608), PacketKind::kOther);
}
