// A simulated scan encoded as OS-1 legacy UDP packets and decoded by the driver's FrameAssembler gives
// the simulator's points back (< 1 mm; the range is already integer millimetres), and the simulator's IMU
// survives the 48-byte IMU packet (float32 g and deg/s).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "fploc/core/xyz.h"
#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using namespace fploc::sim;

TEST(PacketRoundTrip, ScanThroughLegacyPacketsAndAssembler) {
  SimulatorOptions o;
  o.scenario = "room-small-loop-fast";
  o.seed = 4;
  o.shared_dir = FPLOC_SHARED_DIR;
  Simulator sim(FloorPlan{}, o);
  // The metadata JSON the simulator hands to the driver, read back with the driver's own loader.
  const std::string meta_path = ::testing::TempDir() + "/sim_meta.json";
  {
    std::ofstream f(meta_path);
    f << metadata_json(sensor_info_for(sim.lidar().config().beams));
  }
  const os1::SensorInfo info = os1::load_metadata(meta_path);
  std::remove(meta_path.c_str());
  ASSERT_EQ(info.pixels_per_column, 64);
  ASSERT_EQ(info.columns_per_frame, 1024);

  os1::FrameAssembler asmb(info);
  const os1::PacketFormat fmt = os1::PacketFormat::from(info);
  EXPECT_EQ(fmt.lidar_packet_size(), 12608u);
  std::vector<Scan> frames;
  std::vector<SimScan> sent(3);
  for (int k = 0; k < 3; ++k) {
    sim.frame(20 + k, sent[size_t(k)]);
    std::vector<std::vector<uint8_t>> pkts;
    os1::encode_frame(sent[size_t(k)].scan, uint16_t(sent[size_t(k)].scan.frame_id), fmt, pkts);
    ASSERT_EQ(pkts.size(), 64u);
    for (const auto& p : pkts) asmb.add_packet(p.data(), p.size(), frames);
  }
  asmb.flush(frames);
  ASSERT_EQ(frames.size(), 3u);
  const XyzLut lut_sim = sim.lidar().lut();
  const XyzLut lut_drv = make_xyz_lut(frames[0].beams, frames[0].width);
  for (int k = 0; k < 3; ++k) {
    const Scan& a = sent[size_t(k)].scan;
    const Scan& b = frames[size_t(k)];
    EXPECT_EQ(b.missing_columns, 0);
    ASSERT_EQ(b.height, a.height);
    ASSERT_EQ(b.width, a.width);
    std::vector<Eigen::Vector3f> pa, pb;
    scan_to_xyz(a, lut_sim, pa);
    scan_to_xyz(b, lut_drv, pb);
    double worst = 0;
    int valid = 0;
    for (size_t i = 0; i < pa.size(); ++i) {
      ASSERT_EQ(a.range_mm[i], b.range_mm[i]) << "pixel " << i;
      if (a.range_mm[i] == 0) continue;
      ++valid;
      worst = std::max(worst, double((pa[i] - pb[i]).norm()));
    }
    EXPECT_GT(valid, 40000);
    EXPECT_LT(worst, 1e-3) << "frame " << k;
    for (int c = 0; c < a.width; ++c) EXPECT_EQ(a.column_utime[size_t(c)], b.column_utime[size_t(c)]);
    // And the simulator's true (noise-free) geometry: decoded points lie on the labelled surfaces.
    const Eigen::Isometry3d T = sim.ground_truth(a.column_utime[0] * 1e-6).iso();
    for (size_t i = 0; i < pb.size(); i += 97) {
      if (sent[size_t(k)].label[i] != uint8_t(Label::kFloor)) continue;
      // Column 0 only has the pose exactly; others moved a little, so only check the height roughly.
      EXPECT_NEAR((T * pb[i].cast<double>()).z(), 0.0, 0.15);
    }
  }
}

TEST(PacketRoundTrip, Imu) {
  SimulatorOptions o;
  o.scenario = "corridor-loop-medium";
  Simulator sim(FloorPlan{}, o);
  for (size_t k = 0; k < sim.imu().size(); k += 37) {
    const ImuSample& s = sim.imu()[k];
    os1::ImuSample p;
    p.sys_ts_ns = p.accel_ts_ns = p.gyro_ts_ns = uint64_t(std::llround((o.t0_s + s.t) * 1e9));
    for (int i = 0; i < 3; ++i) {
      p.accel_mps2[size_t(i)] = s.accel[i];
      p.gyro_radps[size_t(i)] = s.gyro[i];
    }
    const auto bytes = os1::encode_imu_packet(p);
    os1::ImuSample q;
    ASSERT_TRUE(os1::parse_imu_packet(bytes.data(), bytes.size(), q));
    EXPECT_EQ(q.accel_ts_ns, p.accel_ts_ns);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(q.accel_mps2[size_t(i)], s.accel[i], 1e-5);
      EXPECT_NEAR(q.gyro_radps[size_t(i)], s.gyro[i], 1e-6);
    }
  }
}
