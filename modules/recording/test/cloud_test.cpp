// PointCloud2 -> range image for the other driver layouts: Ouster (organised, ring u16, t u32 ns),
// Robosense-like (unorganised, no ring, float64 absolute timestamp, given ring count with uneven
// beam spacing), Livox-like (line u8, float64 ns timestamp), and bad clouds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fploc/core/xyz.h"
#include "fploc/recording/cloud_to_scan.h"

using namespace fploc;
using namespace fploc::rec;

namespace {

struct Layout {
  std::vector<PointField> fields;
  uint32_t step = 0;
};

// Points of a cylinder room (radius 5 m) seen by `el_deg` beams over `cols` azimuths.
PointCloud2 make(const Layout& L, const std::vector<double>& el_deg, int cols, bool organised, std::vector<uint8_t>& buf,
                 void (*extra)(uint8_t* p, int ring, int col, int cols)) {
  PointCloud2 c;
  c.header.stamp_ns = 1700000000LL * 1000000000LL;
  c.fields = L.fields;
  c.point_step = L.step;
  const int rings = int(el_deg.size());
  c.height = organised ? uint32_t(rings) : 1;
  c.width = organised ? uint32_t(cols) : uint32_t(rings * cols);
  c.row_step = c.width * c.point_step;
  buf.assign(size_t(rings) * cols * L.step, 0);
  size_t n = 0;
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < cols; ++k) {
      // Ouster order: column k at azimuth -k * 360 / cols (clockwise), starting at 0.
      const double az = -2.0 * M_PI * k / cols, el = el_deg[size_t(r)] * M_PI / 180.0;
      const double range = 5.0 / std::cos(el);
      const float xyz[3] = {float(range * std::cos(el) * std::cos(az)), float(range * std::cos(el) * std::sin(az)), float(range * std::sin(el))};
      uint8_t* p = buf.data() + n++ * L.step;
      std::memcpy(p, xyz, 12);
      extra(p, r, k, cols);
    }
  c.data = buf.data();
  c.data_size = buf.size();
  return c;
}

double worst_radius_error(const Scan& s) {
  std::vector<Eigen::Vector3f> xyz;
  scan_to_xyz(s, make_xyz_lut(s.beams, s.width), xyz);
  double w = 0;
  for (const auto& p : xyz)
    if (std::isfinite(p.x())) w = std::max(w, std::abs(std::hypot(p.x(), p.y()) - 5.0));
  return w;
}

}  // namespace

TEST(Cloud, OusterOrganisedRingAndT) {
  Layout L{{{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 16, 7, 1}, {"t", 20, 6, 1}, {"reflectivity", 24, 4, 1}, {"ring", 26, 4, 1}}, 48};
  std::vector<double> el;
  for (int i = 0; i < 32; ++i) el.push_back(21.0 - 42.0 * i / 31);
  std::vector<uint8_t> buf;
  auto c = make(L, el, 512, true, buf, [](uint8_t* p, int ring, int col, int cols) {
    const uint32_t t = uint32_t(uint64_t(col) * 100000000 / cols);
    const uint16_t r = uint16_t(ring);
    const float in = 100.f;
    std::memcpy(p + 16, &in, 4);
    std::memcpy(p + 20, &t, 4);
    std::memcpy(p + 26, &r, 2);
  });
  Scan s;
  CloudStats st;
  std::string err;
  ASSERT_TRUE(cloud_to_scan(c, CloudOptions{}, s, &st, &err)) << err;
  EXPECT_EQ(st.ring_source, "field 'ring'");
  EXPECT_EQ(st.time_source, "field 't'");
  EXPECT_EQ(s.height, 32);
  EXPECT_EQ(s.width, 512);
  EXPECT_EQ(st.collisions, 0u);
  EXPECT_NEAR(s.beams.altitude_deg[0], 21.0, 1e-3);
  EXPECT_NEAR(s.beams.altitude_deg[31], -21.0, 1e-3);
  EXPECT_LT(worst_radius_error(s), 0.003);
  // Column k holds the points fired at azimuth -k * 360/512: measurement id k, time k/512 * 0.1 s.
  EXPECT_EQ(s.range(0, 0) > 0, true);
  EXPECT_NEAR(double(s.column_utime[256] - s.utime), 50000.0, 1.0);
  EXPECT_EQ(s.signal[0], 100);
}

// An organised Ouster-like cloud whose rings sit near half a column off their columns (beam azimuth offsets the
// destaggering leaves, a motion-compensated cloud) with 0.05 column of jitter: binned by azimuth, neighbours of such
// a ring fall into one pixel (collisions, a point lost each time); taken by the cloud's columns, every point has its
// own pixel and the ring's offset becomes its beam azimuth, so each point comes back at its azimuth.
TEST(Cloud, OrganisedCloudOnePointPerPixel) {
  const int R = 64, W = 512;
  const double colw = 2.0 * M_PI / W;
  Layout L{{{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"ring", 26, 4, 1}}, 48};
  std::vector<uint8_t> buf(size_t(R) * W * L.step, 0);
  std::vector<std::vector<double>> az_of(R);  // each ring's point azimuths
  for (int r = 0; r < R; ++r)
    for (int k = 0; k < W; ++k) {
      const double off = (r % 2 ? -0.49 : 0.47) + 0.05 * std::sin(k * 12.9898 + r * 78.233);  // columns
      const double az = std::remainder(-colw * k + M_PI - off * colw, 2.0 * M_PI);
      const double el = (16.6 - 33.2 * r / (R - 1)) * M_PI / 180.0;
      const double range = 5.0 / std::cos(el);
      const float xyz[3] = {float(5.0 * std::cos(az)), float(5.0 * std::sin(az)), float(range * std::sin(el))};
      uint8_t* p = buf.data() + (size_t(r) * W + k) * L.step;
      std::memcpy(p, xyz, 12);
      const uint16_t ring = uint16_t(r);
      std::memcpy(p + 26, &ring, 2);
      az_of[size_t(r)].push_back(std::atan2(double(xyz[1]), double(xyz[0])));
    }
  PointCloud2 c;
  c.fields = L.fields;
  c.point_step = L.step;
  c.height = R, c.width = W, c.row_step = W * L.step;
  c.data = buf.data(), c.data_size = buf.size();
  Scan s;
  CloudStats st;
  std::string err;
  ASSERT_TRUE(cloud_to_scan(c, CloudOptions{}, s, &st, &err)) << err;
  EXPECT_EQ(st.column_source, "organised");
  EXPECT_EQ(st.collisions, 0u);
  EXPECT_EQ(st.kept, uint64_t(R) * W);
  EXPECT_LT(st.max_azimuth_error_deg, 0.1 * 360.0 / W);  // the jitter, not half a column
  // Every point back at its azimuth (each ring's azimuths, sorted, against the image's through the beam model).
  std::vector<Eigen::Vector3f> xyz;
  scan_to_xyz(s, make_xyz_lut(s.beams, s.width), xyz);
  for (int u = 0; u < R; ++u) {
    std::vector<double> got;
    for (int v = 0; v < W; ++v) {
      const auto& p = xyz[size_t(u) * W + v];
      if (std::isfinite(p.x())) got.push_back(std::atan2(double(p.y()), double(p.x())));
    }
    auto want = az_of[size_t(u)];  // row 0 is the top beam: ring 0 here
    ASSERT_EQ(got.size(), want.size()) << u;
    std::sort(got.begin(), got.end());
    std::sort(want.begin(), want.end());
    double worst = 0;
    for (size_t i = 0; i < got.size(); ++i) worst = std::max(worst, std::abs(std::remainder(got[i] - want[i], 2.0 * M_PI)));
    EXPECT_LT(worst, 0.1 * colw) << "ring " << u;
  }
  // The same points with one row's columns out of order: that ring is not organised by column and is binned by
  // azimuth (collisions); the other 63 keep their columns, one point per pixel.
  for (int k = 0; k < W / 2; ++k) std::swap_ranges(buf.data() + size_t(k) * L.step, buf.data() + size_t(k + 1) * L.step,
                                                   buf.data() + size_t(W - 1 - k) * L.step);
  std::swap_ranges(buf.data(), buf.data() + 20 * L.step, buf.data() + 200 * L.step);
  ASSERT_TRUE(cloud_to_scan(c, CloudOptions{}, s, &st, &err)) << err;
  EXPECT_EQ(st.column_source, "organised");
  EXPECT_EQ(st.azimuth_rings, 1);
  EXPECT_EQ(st.stray_points, uint64_t(W));
  EXPECT_GT(st.collisions, 0u);
  for (int u = 1; u < R; ++u)
    for (int v = 0; v < W; ++v) ASSERT_GT(s.range(u, v), 0) << u << " " << v;
}

namespace {
// An organised 64 x 512 cloud as above (rings half a column off their columns, jitter 0.05 column), ring field u16.
struct Organised {
  static constexpr int R = 64, W = 512, step = 48;
  std::vector<uint8_t> buf = std::vector<uint8_t>(size_t(R) * W * step, 0);
  PointCloud2 c;
  Organised() {
    const double colw = 2.0 * M_PI / W;
    for (int r = 0; r < R; ++r)
      for (int k = 0; k < W; ++k) set(r, k, r, (r % 2 ? -0.49 : 0.47) + 0.05 * std::sin(k * 12.9898 + r * 78.233), colw);
    c.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"ring", 26, 4, 1}};
    c.point_step = step;
    c.height = R, c.width = W, c.row_step = W * step;
    c.data = buf.data(), c.data_size = buf.size();
  }
  // The point in row r, column k: ring value `ring`, `off` columns off the column's azimuth.
  void set(int r, int k, int ring, double off, double colw = 2.0 * M_PI / W) {
    const double az = std::remainder(-colw * k + M_PI - off * colw, 2.0 * M_PI);
    const double el = (16.6 - 33.2 * r / (R - 1)) * M_PI / 180.0;
    const float xyz[3] = {float(5.0 * std::cos(az)), float(5.0 * std::sin(az)), float(5.0 * std::tan(el))};
    uint8_t* p = buf.data() + (size_t(r) * W + k) * step;
    std::memcpy(p, xyz, 12);
    const uint16_t rv = uint16_t(ring);
    std::memcpy(p + 26, &rv, 2);
  }
};
}  // namespace

// One bad ring or point of an organised cloud no longer demotes the whole cloud to azimuth binning (where the
// half-column offsets cost collisions in every ring): only the stray points are binned by azimuth.
TEST(Cloud, OrganisedCloudStrayPointsAndRing) {
  Scan s;
  CloudStats st;
  std::string err;
  {  // Three points of ring 10 five columns off their ring's shift (a glitch): those three binned by azimuth.
    Organised o;
    for (int k : {7, 100, 300}) o.set(10, k, 10, 5.3);
    ASSERT_TRUE(cloud_to_scan(o.c, CloudOptions{}, s, &st, &err)) << err;
    EXPECT_EQ(st.column_source, "organised");
    EXPECT_EQ(st.stray_points, 3u);
    EXPECT_EQ(st.azimuth_rings, 0);
    EXPECT_EQ(st.relabelled_points, 0u);
    EXPECT_EQ(s.height, Organised::R);
    EXPECT_LE(st.collisions, 3u);  // at most the strays, each in a pixel of its ring another point holds
    EXPECT_GE(st.kept, uint64_t(Organised::R) * Organised::W - 3);
    for (int u = 0; u < Organised::R; ++u) {
      if (u == 10) continue;
      for (int v = 0; v < Organised::W; ++v) ASSERT_GT(s.range(u, v), 0) << u << " " << v;
    }
  }
  {  // One point with a ring value no row has (64 in a 64-row cloud): a point of its row's ring, where it lies.
    Organised o;
    o.set(20, 33, 64, (20 % 2 ? -0.49 : 0.47));
    ASSERT_TRUE(cloud_to_scan(o.c, CloudOptions{}, s, &st, &err)) << err;
    EXPECT_EQ(st.column_source, "organised");
    EXPECT_EQ(st.relabelled_points, 1u);
    EXPECT_EQ(st.stray_points, 0u);
    EXPECT_EQ(s.height, Organised::R);
    EXPECT_EQ(st.collisions, 0u);
    EXPECT_EQ(st.kept, uint64_t(Organised::R) * Organised::W);
  }
  {  // A ring whose points are shuffled along its row (a scrambled ring): that ring by azimuth, the others organised.
    Organised o;
    const double colw = 2.0 * M_PI / Organised::W;
    for (int k = 0; k < Organised::W; ++k) o.set(5, k, 5, 0.47 + double((k * 37) % 101), colw);
    ASSERT_TRUE(cloud_to_scan(o.c, CloudOptions{}, s, &st, &err)) << err;
    EXPECT_EQ(st.column_source, "organised");
    EXPECT_EQ(st.azimuth_rings, 1);
    EXPECT_EQ(st.stray_points, uint64_t(Organised::W));
    for (int u = 0; u < Organised::R; ++u) {
      if (u == 5) continue;
      for (int v = 0; v < Organised::W; ++v) ASSERT_GT(s.range(u, v), 0) << u << " " << v;
    }
  }
}

TEST(Cloud, NoRingFieldGivenRingCountUnevenBeams) {
  Layout L{{{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 2, 1}, {"timestamp", 16, 8, 1}}, 24};
  // Robosense RS-16-like uneven beams: dense in the middle.
  const std::vector<double> el = {15, 13, 11, 9, 7, 5, 3, 1, -0.33, -1, -3, -5, -7, -9, -11, -15};
  std::vector<uint8_t> buf;
  auto c = make(L, el, 900, false, buf, [](uint8_t* p, int, int col, int cols) {
    const double t = 1700000000.0 + 0.1 * col / cols;
    std::memcpy(p + 16, &t, 8);
  });
  Scan s;
  CloudStats st;
  std::string err;
  CloudOptions o;
  o.rings = 16;
  ASSERT_TRUE(cloud_to_scan(c, o, s, &st, &err)) << err;
  EXPECT_EQ(st.ring_source, "elevation");
  ASSERT_EQ(s.height, 16);
  EXPECT_EQ(s.width, 900);
  for (int r = 0; r < 16; ++r) EXPECT_NEAR(s.beams.altitude_deg[r], el[size_t(r)], 1e-3);
  EXPECT_LT(worst_radius_error(s), 0.003);
  EXPECT_NEAR(double(s.column_utime[450] - s.utime), 50000.0, 2.0);
  // Without the count, gaps > 0.25 deg split the rings: the same 16.
  Scan s2;
  ASSERT_TRUE(cloud_to_scan(c, CloudOptions{}, s2, &st, &err)) << err;
  EXPECT_EQ(s2.height, 16);
}

TEST(Cloud, LivoxLineAndNanosecondTimestamp) {
  Layout L{{{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}, {"tag", 16, 2, 1}, {"line", 17, 2, 1}, {"timestamp", 18, 8, 1}}, 26};
  const std::vector<double> el = {7, 2.5, -2.5, -7};
  std::vector<uint8_t> buf;
  auto c = make(L, el, 360, false, buf, [](uint8_t* p, int ring, int col, int) {
    p[17] = uint8_t(ring);
    const double t = 1.7e18 + 1e5 * col;  // ns
    std::memcpy(p + 18, &t, 8);
  });
  Scan s;
  CloudStats st;
  std::string err;
  ASSERT_TRUE(cloud_to_scan(c, CloudOptions{}, s, &st, &err)) << err;
  EXPECT_EQ(st.ring_source, "field 'line'");
  EXPECT_EQ(s.height, 4);
  EXPECT_EQ(s.utime, int64_t(1.7e15));  // us
}

TEST(Cloud, BadClouds) {
  PointCloud2 c;
  Scan s;
  std::string err;
  c.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}};
  c.point_step = 12;
  c.width = 1;
  c.height = 1;
  EXPECT_FALSE(cloud_to_scan(c, CloudOptions{}, s, nullptr, &err));
  EXPECT_NE(err.find("x/y/z"), std::string::npos);
  c.fields.push_back({"z", 8, 7, 1});
  c.width = 10;
  std::vector<uint8_t> few(12 * 5);
  c.data = few.data();
  c.data_size = few.size();
  EXPECT_FALSE(cloud_to_scan(c, CloudOptions{}, s, nullptr, &err));
  EXPECT_NE(err.find("shorter"), std::string::npos) << err;
}
