// Other beam patterns (issue 13 item 2): each one simulated, written as OS-1 legacy packets with the
// metadata JSON the simulator hands to the driver, read back with the driver's metadata loader and decoded
// by its FrameAssembler: same size, same ranges, same column times.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"
#include "fploc/sim/beam_patterns.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using namespace fploc::sim;

namespace {
void round_trip(const std::string& pattern, int beams) {
  SCOPED_TRACE(pattern);
  SimulatorOptions o;
  o.scenario = "room-small-loop-fast";
  o.beams = pattern;
  o.shared_dir = FPLOC_SHARED_DIR;
  Simulator sim(FloorPlan{}, o);
  ASSERT_EQ(sim.lidar().config().beams.beams(), beams);
  const std::string meta_path = ::testing::TempDir() + "/beams_" + pattern + ".json";
  {
    std::ofstream f(meta_path);
    f << metadata_json(sensor_info_for(sim.lidar().config().beams));
  }
  const os1::SensorInfo info = os1::load_metadata(meta_path);
  std::remove(meta_path.c_str());
  ASSERT_EQ(info.pixels_per_column, beams);
  EXPECT_EQ(info.beams.altitude_deg, sim.lidar().config().beams.altitude_deg);
  os1::FrameAssembler asmb(info);
  const os1::PacketFormat fmt = os1::PacketFormat::from(info);
  SimScan sent;
  sim.frame(10, sent);
  std::vector<std::vector<uint8_t>> pkts;
  os1::encode_frame(sent.scan, uint16_t(sent.scan.frame_id), fmt, pkts);
  ASSERT_EQ(pkts.size(), 64u);  // 1024 columns, 16 per packet
  std::vector<Scan> frames;
  for (const auto& p : pkts) asmb.add_packet(p.data(), p.size(), frames);
  asmb.flush(frames);
  ASSERT_EQ(frames.size(), 1u);
  const Scan& b = frames[0];
  ASSERT_EQ(b.height, beams);
  ASSERT_EQ(b.width, 1024);
  EXPECT_EQ(b.missing_columns, 0);
  int valid = 0;
  for (size_t i = 0; i < b.range_mm.size(); ++i) {
    ASSERT_EQ(sent.scan.range_mm[i], b.range_mm[i]) << "pixel " << i;
    valid += b.range_mm[i] != 0;
  }
  EXPECT_GT(valid, 1024 * beams * 8 / 10);  // a closed room: nearly every ray returns
  EXPECT_EQ(sent.scan.column_utime, b.column_utime);
}
}  // namespace

TEST(BeamPatterns, Os1_32ThroughPackets) { round_trip("os1-32", 32); }
TEST(BeamPatterns, Os1_128ThroughPackets) { round_trip("os1-128", 128); }
TEST(BeamPatterns, Vlp16LikeThroughPackets) { round_trip("vlp16", 16); }

TEST(BeamPatterns, Vlp16LikeAngles) {
  const BeamIntrinsics b = vlp16_like();
  ASSERT_EQ(b.beams(), 16);
  EXPECT_DOUBLE_EQ(b.altitude_deg.front(), 15.0);
  EXPECT_DOUBLE_EQ(b.altitude_deg.back(), -15.0);
}

TEST(BeamPatterns, RealMetadataWhenShared) {
  std::string src;
  const BeamIntrinsics b = beam_pattern("os1-128", FPLOC_SHARED_DIR, &src);
  ASSERT_EQ(b.beams(), 128);
  if (src.find("generated") != std::string::npos) GTEST_SKIP() << "../shared/data/ouster absent: " << src;
  EXPECT_NE(src.find("OS-1-128"), std::string::npos);
  EXPECT_NEAR(b.altitude_deg.front(), 20.95, 1e-9);  // the unit of the real OS-1-128 capture
}

TEST(BeamPatterns, UnknownNameIsOneClearError) {
  try {
    beam_pattern("hdl-64", "", nullptr);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("hdl-64"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("vlp16"), std::string::npos);
  }
}
