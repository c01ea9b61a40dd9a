// point_cloud2_t: what `fploc import` writes (header encoded here + the recording's point bytes) is the
// LCM encoding of the whole message, and a cloud that went through the message (encode, decode, view)
// converts to the same scan_t, byte for byte, as the cloud converted directly (`fploc import --decode`),
// for the Ouster, Velodyne, Hesai, Robosense and Livox driver layouts, big-endian points and a stamp
// with nanoseconds below the microsecond.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fploc/adapters/point_cloud2_t.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/recording/cloud_to_scan.h"

using namespace fploc;
using namespace fploc::rec;

namespace {

struct Layout {
  std::string name;
  std::vector<PointField> fields;
  uint32_t step;
  bool organised;
  bool big_endian;
  int rings_option;  // CloudOptions.rings (0: ring field or gaps)
};

template <class T>
void put(uint8_t* p, T v, bool be) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (be) std::reverse(b, b + sizeof(T));
  std::memcpy(p, b, sizeof(T));
}

// A 16-beam (uneven spacing near the horizon, like a Robosense RS-16) scan of a 10 x 6 m box room.
PointCloud2 make(const Layout& L, std::vector<uint8_t>& buf) {
  const std::vector<double> el = {-15, -13, -11, -9, -7, -5, -3, -1, 0.67, 1.33, 3, 5, 7, 9, 11, 15};
  const int cols = 360, rings = int(el.size());
  PointCloud2 c;
  c.header.stamp_ns = 1700000000LL * 1000000000LL + 123456789;  // 789 ns below the microsecond
  c.header.frame_id = "lidar";
  c.fields = L.fields;
  c.point_step = L.step;
  c.is_bigendian = L.big_endian;
  c.height = L.organised ? uint32_t(rings) : 1;
  c.width = L.organised ? uint32_t(cols) : uint32_t(rings * cols);
  c.row_step = c.width * c.point_step;
  buf.assign(size_t(rings) * cols * L.step, 0);
  size_t n = 0;
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < cols; ++k) {
      const double az = -2.0 * M_PI * k / cols, e = el[size_t(r)] * M_PI / 180.0;
      const double d[3] = {std::cos(e) * std::cos(az), std::cos(e) * std::sin(az), std::sin(e)};
      double t = 1e9;
      const double lo[3] = {-4, -2.5, -1.5}, hi[3] = {6, 3.5, 2};
      for (int i = 0; i < 3; ++i) {
        if (d[i] > 1e-9) t = std::min(t, hi[i] / d[i]);
        if (d[i] < -1e-9) t = std::min(t, lo[i] / d[i]);
      }
      uint8_t* p = buf.data() + n++ * L.step;
      const double dt = 0.1 * k / cols;  // seconds after the stamp
      for (const auto& f : L.fields) {
        uint8_t* q = p + f.offset;
        if (f.name == "x" || f.name == "y" || f.name == "z") put<float>(q, float(t * d[f.name[0] - 'x']), L.big_endian);
        else if (f.name == "intensity") put<float>(q, float((r * 13 + k) % 200), L.big_endian);
        else if (f.name == "reflectivity") put<uint16_t>(q, uint16_t(r * 7), L.big_endian);
        else if (f.name == "ring") put<uint16_t>(q, uint16_t(r), L.big_endian);
        else if (f.name == "line") *q = uint8_t(r);
        else if (f.name == "t") put<uint32_t>(q, uint32_t(dt * 1e9), L.big_endian);
        else if (f.name == "time") put<float>(q, float(dt), L.big_endian);
        else if (f.name == "timestamp")
          put<double>(q, L.name == "livox" ? double(c.header.stamp_ns) + dt * 1e9 : c.header.stamp_ns * 1e-9 + dt, L.big_endian);
      }
    }
  c.data = buf.data();
  c.data_size = buf.size();
  return c;
}

std::vector<uint8_t> scan_bytes(const Scan& s) {
  scan_t m;
  adapters::to_msg(s, m);
  std::vector<uint8_t> b(size_t(m.getEncodedSize()));
  m.encode(b.data(), 0, int(b.size()));
  return b;
}

const std::vector<Layout>& layouts() {
  static const std::vector<Layout> L = {
      {"ouster", {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 16, 7, 1}, {"t", 20, 6, 1}, {"reflectivity", 24, 4, 1}, {"ring", 26, 4, 1}}, 48, true, false, 0},
      {"velodyne", {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}, {"ring", 16, 4, 1}, {"time", 18, 7, 1}}, 22, false, false, 0},
      {"hesai", {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}, {"timestamp", 16, 8, 1}}, 24, false, false, 0},  // no ring: from elevation gaps
      {"robosense", {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}, {"timestamp", 16, 8, 1}}, 24, false, false, 16},
      {"livox", {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}, {"line", 16, 2, 1}, {"timestamp", 18, 8, 1}}, 26, false, false, 0},
      {"velodyne-big-endian", {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}, {"ring", 16, 4, 1}, {"time", 18, 7, 1}}, 22, false, true, 0},
  };
  return L;
}

}  // namespace

TEST(PointCloud2Msg, HeaderPlusPointBytesIsTheEncodedMessage) {
  for (const auto& L : layouts()) {
    std::vector<uint8_t> buf, head;
    const PointCloud2 c = make(L, buf);
    point_cloud2_t m;
    adapters::to_msg(c, 42, "/" + L.name + "_points", m);
    std::vector<uint8_t> whole(size_t(m.getEncodedSize()));
    ASSERT_EQ(m.encode(whole.data(), 0, int(whole.size())), int(whole.size()));
    adapters::encode_without_data(c, 42, "/" + L.name + "_points", head);
    head.insert(head.end(), c.data, c.data + c.data_size);
    EXPECT_EQ(head, whole) << L.name;
  }
}

TEST(PointCloud2Msg, ConvertedOnReplayGivesTheScanOfTheImporter) {
  for (const auto& L : layouts()) {
    SCOPED_TRACE(L.name);
    std::vector<uint8_t> buf, head;
    const PointCloud2 c = make(L, buf);
    CloudOptions opt;
    opt.rings = L.rings_option;
    Scan direct, replayed;
    CloudStats st;
    std::string err;
    ASSERT_TRUE(cloud_to_scan(c, opt, direct, &st, &err)) << err;
    EXPECT_EQ(direct.height, 16);
    EXPECT_EQ(st.kept, st.points);

    // What the importer writes, decoded as the cloud-to-scan node receives it.
    adapters::encode_without_data(c, 7, "/points", head);
    head.insert(head.end(), c.data, c.data + c.data_size);
    point_cloud2_t m;
    ASSERT_EQ(m.decode(head.data(), 0, int(head.size())), int(head.size()));
    EXPECT_EQ(m.utime * 1000 + m.utime_ns, c.header.stamp_ns);
    PointCloud2 view;
    ASSERT_TRUE(adapters::from_msg(m, view, &err)) << err;
    ASSERT_TRUE(cloud_to_scan(view, opt, replayed, nullptr, &err)) << err;
    EXPECT_EQ(scan_bytes(replayed), scan_bytes(direct));
    EXPECT_GT(direct.utime, 0);
  }
}

TEST(PointCloud2Msg, InconsistentMessageIsRejected) {
  point_cloud2_t m{};
  m.source = "/points";
  m.size = 10;  // but no data
  PointCloud2 view;
  std::string err;
  EXPECT_FALSE(adapters::from_msg(m, view, &err));
  EXPECT_NE(err.find("/points"), std::string::npos) << err;
}
