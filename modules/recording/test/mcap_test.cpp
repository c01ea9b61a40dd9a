// MCAP files written by an independent writer (the MCAP project's @mcap/core with @foxglove/cdr, run by
// Node: tests/import/write_mcap.js): chunks none/zstd/lz4 and unchunked, a Velodyne-layout and a
// Hesai-layout PointCloud2 stream of a box room, Imu, LaserScan, Odometry, tf.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

#include "fploc/core/xyz.h"
#include "fploc/recording/cloud_to_scan.h"
#include "fploc/recording/recording.h"
#include "fploc/recording/ros_msgs.h"
#include "test_util.h"

using namespace fploc;
using namespace fploc::rec;
using namespace fploc::rec::test;

namespace {

std::string write_mcap(const std::string& compression, const std::string& chunking) {
  const std::string dir = std::string(FPLOC_SOURCE_DIR) + "/tests/import";
  if (!std::filesystem::exists(dir + "/node_modules/@mcap/core")) return "";
  const std::string out = ::testing::TempDir() + "/t_" + compression + "_" + chunking + ".mcap";
  const std::string cmd = "cd '" + dir + "' && node write_mcap.js '" + out + "' " + compression + " " + chunking;
  if (std::system(cmd.c_str()) != 0) return "!";
  return out;
}

// Distance of p to the surface of the box room the writer's rays hit.
double box_distance(const Eigen::Vector3f& p) {
  const double lo[3] = {-4, -2.5, -1.5}, hi[3] = {6, 3.5, 2.0};
  double d = 1e9;
  for (int i = 0; i < 3; ++i) d = std::min({d, std::abs(p[i] - lo[i]), std::abs(p[i] - hi[i])});
  return d;
}

}  // namespace

class Mcap : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(Mcap, IndependentWriter) {
  const auto [comp, chunking] = GetParam();
  const std::string path = write_mcap(comp, chunking);
  if (path.empty()) GTEST_SKIP() << "tests/import/node_modules missing (scripts/setup-web.sh installs @mcap/core)";
  ASSERT_NE(path, "!") << "node write_mcap.js failed";
  std::string err;
  auto r = open_recording(path, &err);
  ASSERT_TRUE(r) << err;
  EXPECT_EQ(r->format(), "mcap");
  std::map<std::string, int> count;
  RawMessage m;
  int64_t last_t = 0;
  while (r->next(m)) {
    const Connection& c = r->connections().at(m.conn);
    ASSERT_EQ(c.encoding, Encoding::kCdr);
    ++count[c.topic];
    EXPECT_GE(m.time_ns, last_t);
    last_t = m.time_ns;
    if (c.type == "sensor_msgs/PointCloud2") {
      PointCloud2 pc;
      ASSERT_TRUE(decode(m.data, m.size, c.encoding, pc, &err)) << err;
      EXPECT_EQ(pc.width, 16u * 1800u);
      EXPECT_EQ(pc.header.stamp_ns, m.time_ns);
      Scan s;
      CloudStats st;
      ASSERT_TRUE(cloud_to_scan(pc, CloudOptions{}, s, &st, &err)) << err;
      EXPECT_EQ(st.ring_source, c.topic == "/velodyne_points" ? "field 'ring'" : "elevation");
      EXPECT_EQ(s.height, 16);
      EXPECT_EQ(s.width, 1800);
      EXPECT_EQ(st.kept, 16u * 1800u);
      EXPECT_EQ(st.collisions, 0u);
      EXPECT_LT(st.max_azimuth_error_deg, 0.1 + 1e-3);
      for (int b = 0; b < 16; ++b) EXPECT_NEAR(s.beams.altitude_deg[b], 15.0 - 2.0 * b, 1e-3);  // top beam first
      // Back to XYZ with fploc's beam model: every point lies on the room's walls (half a column of
      // azimuth at <= 8 m is < 1.4 cm).
      std::vector<Eigen::Vector3f> xyz;
      scan_to_xyz(s, make_xyz_lut(s.beams, s.width), xyz);
      double worst = 0;
      for (const auto& p : xyz)
        if (std::isfinite(p.x())) worst = std::max(worst, box_distance(p));
      EXPECT_LT(worst, 0.02) << c.topic;
      // Column times: the writer's points sweep 0.1 s per turn.
      const int64_t t0 = pc.header.stamp_ns / 1000;
      int64_t lo = INT64_MAX, hi = INT64_MIN;
      for (int64_t t : s.column_utime) lo = std::min(lo, t), hi = std::max(hi, t);
      EXPECT_NEAR(double(lo - t0), 0.0, 60.0);
      EXPECT_NEAR(double(hi - t0), 1e5, 200.0);
    } else if (c.type == "sensor_msgs/Imu") {
      Imu u;
      ASSERT_TRUE(decode(m.data, m.size, c.encoding, u, &err)) << err;
      EXPECT_DOUBLE_EQ(u.linear_acceleration[2], 9.81);
      EXPECT_DOUBLE_EQ(u.angular_velocity[1], -0.02);
      EXPECT_EQ(u.header.frame_id, "imu");
    } else if (c.type == "sensor_msgs/LaserScan") {
      LaserScan l;
      ASSERT_TRUE(decode(m.data, m.size, c.encoding, l, &err)) << err;
      ASSERT_EQ(l.ranges.size(), 181u);
      ASSERT_EQ(l.intensities.size(), 181u);
      EXPECT_FLOAT_EQ(l.ranges[100], 2.0f);
      EXPECT_FLOAT_EQ(l.range_max, 30.f);
    } else if (c.type == "nav_msgs/Odometry") {
      Odometry o;
      ASSERT_TRUE(decode(m.data, m.size, c.encoding, o, &err)) << err;
      EXPECT_EQ(o.pose.child_frame_id, "base_link");
      EXPECT_NEAR(o.pose.t[0], 2.0 * o.pose.t[1], 1e-12);
    } else if (c.type == "tf2_msgs/TFMessage") {
      std::vector<Transform> ts;
      ASSERT_TRUE(decode_tf(m.data, m.size, c.encoding, ts, &err)) << err;
      ASSERT_EQ(ts.size(), 1u);
      EXPECT_EQ(ts[0].header.frame_id, "odom");
    } else {
      ADD_FAILURE() << "unexpected type " << c.type;
    }
  }
  EXPECT_EQ(r->error(), "");
  EXPECT_EQ(count["/velodyne_points"], 3);
  EXPECT_EQ(count["/hesai_points"], 3);
  EXPECT_EQ(count["/imu"], 20);
  EXPECT_EQ(count["/scan"], 3);
  EXPECT_EQ(count["/odom"], 10);
  EXPECT_EQ(count["/tf"], 10);

  // Truncated: one error with the byte offset; the messages before it are the same.
  const auto bytes = slurp(path);
  const auto all = read_all(bytes.data(), bytes.size(), &err);
  ASSERT_EQ(err, "");
  const auto part = read_all(bytes.data(), bytes.size() / 2, &err, "half.mcap");
  EXPECT_NE(err.find("half.mcap: "), std::string::npos);
  EXPECT_NE(err.find(" at byte "), std::string::npos) << err;
  ASSERT_LT(part.size(), all.size());
  for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i].data, all[i].data);

  // CRCs: one flipped bit inside the first chunk (chunked files: the chunk's CRC-32, or the decompressor,
  // names that chunk's byte offset) or inside a message (unchunked: the data section's CRC-32 at the
  // Data End record). The writer computes both CRCs.
  size_t at = 8, target = 0, data_end = 0;
  std::string want;
  while (at + 9 <= bytes.size()) {
    const uint8_t op = bytes[at];
    uint64_t len;
    std::memcpy(&len, &bytes[at + 1], 8);
    if (op == 0x06 && !target) {
      target = at + 9 + len / 2 + 20;
      want = "chunk at byte " + std::to_string(at) + " (" + (std::string(comp) == "none" ? "none" : comp) + "): ";
    }
    if (op == 0x05 && !target) target = at + 9 + len - 3;
    if (op == 0x0F) data_end = at;
    if (op == 0x02) break;
    at += 9 + len;
  }
  ASSERT_GT(target, 0u);
  if (want.empty()) {
    ASSERT_GT(data_end, 0u);
    uint32_t crc;
    std::memcpy(&crc, &bytes[data_end + 9], 4);
    ASSERT_NE(crc, 0u) << "the writer did not record a data section CRC";
    want = "data section (bytes 0.." + std::to_string(data_end) + "): CRC-32 ";
  }
  auto bad = bytes;
  bad[target] ^= 0x10;
  const auto got = read_all(bad.data(), bad.size(), &err, "bad.mcap");
  EXPECT_EQ(err.rfind("bad.mcap: " + want, 0), 0u) << err;
  if (std::string(comp) == "none") {
    EXPECT_NE(err.find("CRC-32"), std::string::npos) << err;
  }
  // A damaged chunk stops before its messages; the data section CRC is only known at its end (the
  // messages were delivered, the import still ends with the error).
  if (std::string(chunking) == "chunked") {
    EXPECT_LT(got.size(), all.size());
  }
}

INSTANTIATE_TEST_SUITE_P(Writers, Mcap,
                         ::testing::Values(std::make_pair("none", "chunked"), std::make_pair("zstd", "chunked"),
                                           std::make_pair("lz4", "chunked"), std::make_pair("none", "unchunked")),
                         [](const auto& i) { return std::string(i.param.first) + "_" + i.param.second; });
