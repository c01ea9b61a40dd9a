#include "fploc/os1/packet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

using namespace fploc;
using namespace fploc::os1;

namespace {

SensorInfo info_for(int beams, UdpProfile p = UdpProfile::kLegacy, const std::string& mode = "1024x10") {
  std::vector<double> alt, az;
  for (int i = 0; i < beams; ++i) {
    alt.push_back(16.0 - 32.0 * i / beams);
    az.push_back(i % 2 ? 1.5 : -1.5);
  }
  return make_sensor_info(alt, az, mode, p);
}

Scan random_scan(const SensorInfo& info, uint32_t seed) {
  Scan s;
  s.resize(info.pixels_per_column, info.columns_per_frame);
  std::mt19937 rng(seed);
  for (auto& r : s.range_mm) r = rng() % 5 == 0 ? 0 : rng() % 120000;
  for (auto& v : s.signal) v = uint16_t(rng());
  for (auto& v : s.reflectivity) v = uint8_t(rng());
  for (int c = 0; c < s.width; ++c) s.column_utime[c] = 1'600'000'000'000'000 + c * 97;
  s.beams = info.beams;
  return s;
}

}  // namespace

TEST(Packet, Sizes) {
  EXPECT_EQ(PacketFormat::from(info_for(64)).lidar_packet_size(), 12608u);
  EXPECT_EQ(PacketFormat::from(info_for(16)).lidar_packet_size(), 16u * (16 + 16 * 12 + 4));
  EXPECT_EQ(PacketFormat::from(info_for(128, UdpProfile::kRng19Rfl8Sig16Nir16)).lidar_packet_size(), 24832u);
}

class RoundTrip : public ::testing::TestWithParam<std::tuple<int, UdpProfile>> {};

TEST_P(RoundTrip, EncodeThenAssemble) {
  const auto [beams, profile] = GetParam();
  const SensorInfo info = info_for(beams, profile);
  const Scan in = random_scan(info, uint32_t(beams));
  const PacketFormat f = PacketFormat::from(info);
  std::vector<std::vector<uint8_t>> pk;
  encode_frame(in, 4242, f, pk);
  ASSERT_EQ(pk.size(), 64u);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  for (auto& p : pk) EXPECT_EQ(fa.add_packet(p.data(), p.size(), out), PacketError::kNone);
  ASSERT_EQ(out.size(), 1u);  // published as soon as complete
  const Scan& s = out[0];
  EXPECT_EQ(s.frame_id, 4242);
  EXPECT_EQ(s.missing_columns, 0);
  EXPECT_EQ(s.status, ScanStatus::kOk);
  const uint32_t mask = profile == UdpProfile::kLegacy ? 0xFFFFF : 0x7FFFF;
  for (size_t i = 0; i < in.range_mm.size(); ++i) {
    ASSERT_EQ(s.range_mm[i], std::min(in.range_mm[i], mask)) << i;
    ASSERT_EQ(s.signal[i], in.signal[i]) << i;
    ASSERT_EQ(s.reflectivity[i], in.reflectivity[i]) << i;
  }
  EXPECT_EQ(s.column_utime, in.column_utime);
  EXPECT_EQ(s.utime, in.column_utime[0]);
  EXPECT_EQ(fa.stats().complete_frames, 1u);
  // Column headers: encoder count and measurement ids.
  LidarPacketView v;
  ASSERT_TRUE(v.reset(f, pk[3].data(), pk[3].size()));
  EXPECT_EQ(v.column(1).measurement_id, 49);
  EXPECT_EQ(v.column(1).frame_id, 4242);
  if (profile == UdpProfile::kLegacy) {
    EXPECT_EQ(v.column(1).encoder_count, 49u * 90112u / 1024u);
  }
}

INSTANTIATE_TEST_SUITE_P(Beams, RoundTrip,
                         ::testing::Values(std::make_tuple(16, UdpProfile::kLegacy), std::make_tuple(32, UdpProfile::kLegacy),
                                           std::make_tuple(64, UdpProfile::kLegacy), std::make_tuple(128, UdpProfile::kLegacy),
                                           std::make_tuple(64, UdpProfile::kRng19Rfl8Sig16Nir16),
                                           std::make_tuple(128, UdpProfile::kRng19Rfl8Sig16Nir16)));

TEST(Packet, MissingColumnsMarkedAndNeverMerged) {
  const SensorInfo info = info_for(64);
  const PacketFormat f = PacketFormat::from(info);
  Scan a = random_scan(info, 1), b = random_scan(info, 2);
  std::vector<std::vector<uint8_t>> pa, pb;
  encode_frame(a, 10, f, pa);
  encode_frame(b, 11, f, pb);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  for (size_t i = 0; i < pa.size(); ++i)
    if (i != 5) fa.add_packet(pa[i].data(), pa[i].size(), out);  // lose packet 5 of frame 10
  EXPECT_TRUE(out.empty());
  fa.add_packet(pb[0].data(), pb[0].size(), out);  // next frame starts: frame 10 goes out incomplete
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].frame_id, 10);
  EXPECT_EQ(out[0].missing_columns, 16);
  EXPECT_EQ(out[0].status, ScanStatus::kIncomplete);
  for (int c = 0; c < 1024; ++c) EXPECT_EQ(out[0].column_valid[c], (c >= 80 && c < 96) ? 0 : 1) << c;
  EXPECT_EQ(out[0].range(3, 85), 0u);
  // The late packet of frame 10 is dropped, not merged into frame 11.
  EXPECT_EQ(fa.add_packet(pa[5].data(), pa[5].size(), out), PacketError::kStaleFrame);
  for (size_t i = 1; i < pb.size(); ++i) fa.add_packet(pb[i].data(), pb[i].size(), out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].frame_id, 11);
  EXPECT_EQ(out[1].missing_columns, 0);
  EXPECT_EQ(out[1].range_mm, b.range_mm);
  EXPECT_EQ(fa.stats().stale_packets, 1u);
  EXPECT_EQ(fa.stats().missing_columns, 16u);
  EXPECT_EQ(fa.stats().frames, 2u);
  EXPECT_EQ(fa.stats().complete_frames, 1u);
}

TEST(Packet, InvalidColumnStatusAndDuplicates) {
  const SensorInfo info = info_for(32);
  const PacketFormat f = PacketFormat::from(info);
  Scan a = random_scan(info, 3);
  a.column_valid[17] = 0;
  std::vector<std::vector<uint8_t>> pa;
  encode_frame(a, 7, f, pa);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  EXPECT_EQ(fa.add_packet(pa[0].data(), pa[0].size(), out), PacketError::kNone);
  EXPECT_EQ(fa.add_packet(pa[0].data(), pa[0].size(), out), PacketError::kDuplicateColumn);
  EXPECT_EQ(fa.add_packet(pa[1].data(), pa[1].size(), out), PacketError::kInvalidColumns);
  for (size_t i = 2; i < pa.size(); ++i) fa.add_packet(pa[i].data(), pa[i].size(), out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].missing_columns, 1);
  EXPECT_EQ(out[0].column_valid[17], 0);
  EXPECT_EQ(fa.stats().duplicate_columns, 16u);
  EXPECT_EQ(fa.stats().invalid_columns, 1u);
}

TEST(Packet, GarbageIsCountedNeverCrashes) {
  const SensorInfo info = info_for(64);
  const PacketFormat f = PacketFormat::from(info);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  std::vector<uint8_t> buf(f.lidar_packet_size());
  EXPECT_EQ(fa.add_packet(buf.data(), buf.size() - 1, out), PacketError::kWrongSize);  // truncated
  EXPECT_EQ(fa.add_packet(nullptr, 0, out), PacketError::kWrongSize);
  std::mt19937 rng(5);
  int bad = 0;
  for (int i = 0; i < 200; ++i) {
    for (auto& b : buf) b = uint8_t(rng());
    if (fa.add_packet(buf.data(), buf.size(), out) != PacketError::kNone) ++bad;
  }
  fa.flush(out);
  EXPECT_GT(bad, 150);
  EXPECT_EQ(fa.stats().wrong_size, 2u);
  EXPECT_GT(fa.stats().bad_measurement_id, 1000u);
  EXPECT_EQ(fa.stats().packets, 202u);
}

TEST(Imu, RoundTripSi) {
  ImuSample s;
  s.sys_ts_ns = 123456789012345ULL;
  s.accel_ts_ns = s.sys_ts_ns + 10;
  s.gyro_ts_ns = s.sys_ts_ns + 20;
  s.accel_mps2 = {-0.3, 0.2, 9.77};
  s.gyro_radps = {0.01, -0.02, 1.5};
  auto b = encode_imu_packet(s);
  ImuSample r;
  ASSERT_TRUE(parse_imu_packet(b.data(), b.size(), r));
  EXPECT_EQ(r.sys_ts_ns, s.sys_ts_ns);
  EXPECT_EQ(r.accel_ts_ns, s.accel_ts_ns);
  EXPECT_EQ(r.gyro_ts_ns, s.gyro_ts_ns);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.accel_mps2[i], s.accel_mps2[i], 1e-5);
    EXPECT_NEAR(r.gyro_radps[i], s.gyro_radps[i], 1e-6);
  }
  // 1 g on z reads as standard gravity.
  float one = 1.0f;
  std::memcpy(b.data() + 32, &one, 4);
  ASSERT_TRUE(parse_imu_packet(b.data(), b.size(), r));
  EXPECT_DOUBLE_EQ(r.accel_mps2[2], 9.80665);
  EXPECT_FALSE(parse_imu_packet(b.data(), 47, r));
  EXPECT_FALSE(parse_imu_packet(b.data(), 49, r));
  float nan = std::nanf("");
  std::memcpy(b.data() + 40, &nan, 4);
  EXPECT_FALSE(parse_imu_packet(b.data(), b.size(), r));
}

TEST(Packet, AzimuthWindowWrappingZero) {
  SensorInfo info = info_for(16);
  info.column_window_first = 1000, info.column_window_last = 15;  // 40 columns around 0
  const PacketFormat f = PacketFormat::from(info);
  Scan a = random_scan(info, 9);
  std::vector<std::vector<uint8_t>> pa;
  encode_frame(a, 77, f, pa);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  fa.add_packet(pa[0].data(), pa[0].size(), out);
  fa.add_packet(pa[62].data(), pa[62].size(), out);
  EXPECT_TRUE(out.empty());
  fa.add_packet(pa[63].data(), pa[63].size(), out);  // all 40 window columns in: published now
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].missing_columns, 0);
  EXPECT_EQ(out[0].status, ScanStatus::kOk);
  EXPECT_EQ(out[0].column_valid[500], 0);  // outside the window: invalid but not "missing"
  EXPECT_EQ(out[0].range(5, 1010), a.range(5, 1010));
  EXPECT_EQ(out[0].utime, a.column_utime[0]);
}
