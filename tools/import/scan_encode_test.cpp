// encode_scan gives the bytes of to_msg() + scan_t::encode() for every shape of Scan the importer
// writes (OS-1 frames from the ouster_ros bag, point-cloud scans) and for ragged ones.
#include <gtest/gtest.h>

#include <filesystem>
#include <fploc/scan_t.hpp>
#include <random>

#include "fploc/adapters/scan_t.h"
#include "fploc/recording/ouster_packets.h"
#include "fploc/recording/recording.h"
#include "fploc/recording/ros_msgs.h"
#include "scan_encode.h"

namespace fploc::import {
namespace {

std::vector<uint8_t> reference(const Scan& s) {
  scan_t m;
  fploc::adapters::to_msg(s, m);
  std::vector<uint8_t> b(size_t(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, int(b.size())), int(b.size()));
  return b;
}

Scan random_scan(std::mt19937& rng, int h, int w) {
  Scan s;
  s.resize(h, w);
  s.utime = int64_t(rng()) << 20;
  s.seq = rng();
  s.frame_id = int32_t(rng() & 0xFFFF);
  s.sensor = "test " + std::to_string(rng());
  for (auto& v : s.range_mm) v = rng();
  for (auto& v : s.signal) v = uint16_t(rng());  // half of them above 32767: saturated
  for (auto& v : s.reflectivity) v = uint8_t(rng());
  for (auto& v : s.column_utime) v = int64_t(rng()) * 1000 - 5;
  for (auto& v : s.column_valid) v = uint8_t(rng() % 3);
  for (int u = 0; u < h; ++u) {
    s.beams.altitude_deg.push_back(std::uniform_real_distribution<double>(-45, 45)(rng));
    s.beams.azimuth_deg.push_back(std::uniform_real_distribution<double>(-4, 4)(rng));
    s.beams.pixel_shift_by_row.push_back(int(rng() % 40) - 20);
  }
  s.beams.beam_offset_mm = 15.806;
  s.missing_columns = int32_t(rng() % 100);
  s.status = ScanStatus::kIncomplete;
  return s;
}

TEST(ScanEncode, RandomScansEncodeLikeLcm) {
  std::mt19937 rng(7);
  for (auto [h, w] : {std::pair{1, 1}, {16, 1800}, {64, 1024}, {128, 512}, {3, 7}}) {
    Scan s = random_scan(rng, h, w);
    std::vector<uint8_t> got;
    encode_scan(s, got);
    EXPECT_EQ(got, reference(s)) << h << "x" << w;
  }
}

TEST(ScanEncode, RaggedScansEncodeLikeLcm) {
  std::mt19937 rng(11);
  Scan s = random_scan(rng, 8, 20);
  s.signal.clear();                    // no signal: zeros
  s.reflectivity.resize(50);           // short: zero padded
  s.column_utime.resize(5);            // short: utime
  s.measurement_id.resize(3);          // short: index
  s.column_valid.clear();              // none: valid
  s.beams.altitude_deg.push_back(1.0); // longer than height: cut
  s.beams.azimuth_deg.resize(2);
  s.beams.pixel_shift_by_row.clear();
  s.sensor.clear();
  std::vector<uint8_t> got;
  encode_scan(s, got);
  EXPECT_EQ(got, reference(s));
}

TEST(ScanEncode, OusterBagFrameEncodesLikeLcm) {
  const std::string bag = std::string(FPLOC_SHARED_DIR) + "/data/ouster/512x10_raw.bag";
  if (!std::filesystem::exists(bag)) GTEST_SKIP() << "no " << bag << " (../shared/data absent)";
  std::string err;
  auto r = rec::open_recording(bag, &err);
  ASSERT_TRUE(r) << err;
  rec::OusterPackets ouster;
  std::vector<Scan> frames;
  rec::RawMessage m;
  while (r->next(m)) {
    const auto& c = r->connections().at(m.conn);
    if (c.type == "std_msgs/String") {
      std::string text;
      ASSERT_TRUE(rec::decode_string(m.data, m.size, c.encoding, text, &err)) << err;
      ASSERT_TRUE(ouster.set_metadata(text, c.topic, &err)) << err;
    } else {
      const uint8_t* buf = nullptr;
      size_t n = 0;
      ASSERT_TRUE(rec::decode_bytes(m.data, m.size, c.encoding, &buf, &n, &err)) << err;
      os1::ImuSample imu;
      ouster.add(buf, n, m.time_ns, frames, &imu);
    }
  }
  ouster.flush(frames);
  ASSERT_FALSE(frames.empty());
  for (const Scan& s : frames) {
    std::vector<uint8_t> got;
    encode_scan(s, got);
    EXPECT_EQ(got, reference(s));
  }
}

}  // namespace
}  // namespace fploc::import
