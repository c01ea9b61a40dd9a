#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include "fploc/core/xyz.h"
#include "fploc/os1/packet.h"
#include "fploc/os1/pcap.h"
#include "fploc/os1/source.h"
#include "test_util.h"

using namespace fploc;
using namespace fploc::os1;
using fploc::os1::test::ouster_dir;

namespace {
Scan decode_first_frame(const std::string& pcap, const SensorInfo& info) {
  PcapReader r;
  EXPECT_TRUE(r.open(pcap)) << r.error();
  FrameAssembler fa(info);
  std::vector<Scan> frames;
  UdpDatagram d;
  while (r.next(d))
    if (d.size == fa.format().lidar_packet_size()) fa.add_packet(d.data, d.size, frames);
  fa.flush(frames);
  EXPECT_FALSE(frames.empty());
  return frames.empty() ? Scan{} : frames[0];
}

// Median distance between vertically adjacent pixels, with or without destaggering.
double median_vertical_step(const Scan& s, const XyzLut& lut, bool destagger) {
  std::vector<Eigen::Vector3f> img(size_t(s.height) * s.width, Eigen::Vector3f::Constant(NAN));
  for (int u = 0; u < s.height; ++u)
    for (int c = 0; c < s.width; ++c) {
      const int col = destagger ? destagger_column(s.beams, u, c, s.width) : c;
      img[size_t(u) * s.width + col] = lut_point(lut, u, c, s.range(u, c));
    }
  std::vector<double> d;
  for (int u = 0; u + 1 < s.height; ++u)
    for (int c = 0; c < s.width; ++c) {
      const auto& a = img[size_t(u) * s.width + c];
      const auto& b = img[size_t(u + 1) * s.width + c];
      if (a.allFinite() && b.allFinite()) d.push_back((a - b).norm());
    }
  std::nth_element(d.begin(), d.begin() + long(d.size() / 2), d.end());
  return d[d.size() / 2];
}
}  // namespace

// The XYZ model and destaggering on real data: with the right pixel_shift_by_row, vertical neighbours
// in the destaggered image are much closer than in the staggered one (for the reduced file the shifts
// are the SDK defaults).
TEST(Xyz, DestaggeredImageIsContinuous) {
  FPLOC_REQUIRE_SHARED();
  for (auto [pcap, meta] : {std::pair{"/OS-1-64_1024x10_fw20.pcap", "/OS-1-64_sensor_config_reduced.json"},
                            std::pair{"/OS-1-32-G_v2.1.1_1024x10.pcap", "/OS-1-32-G_v2.1.1_1024x10.json"}}) {
    SCOPED_TRACE(pcap);
    const SensorInfo info = load_metadata(ouster_dir() + meta);
    const Scan s = decode_first_frame(ouster_dir() + pcap, info);
    ASSERT_EQ(s.missing_columns, 0);
    const XyzLut lut = make_xyz_lut(info.beams, info.columns_per_frame);
    const double stag = median_vertical_step(s, lut, false), dest = median_vertical_step(s, lut, true);
    EXPECT_LT(dest, 0.7 * stag) << "destaggered " << dest << " m, staggered " << stag << " m";
    // Points are where the ranges say: |p| ~ range within the beam offset and lidar_to_sensor z.
    int checked = 0;
    for (int u = 0; u < s.height; u += 7)
      for (int c = 0; c < s.width; c += 13) {
        const uint32_t r = s.range(u, c);
        if (r < 1000) continue;
        const Eigen::Vector3f p = lut_point(lut, u, c, r);
        const Eigen::Vector3f lidar_origin(0, 0, float(info.beams.lidar_to_sensor[11] * 1e-3));
        EXPECT_NEAR((p - lidar_origin).norm(), r * 1e-3, 0.02) << u << "," << c;
        ++checked;
      }
    EXPECT_GT(checked, 50);
  }
}

// Encoded packets over a real loopback UDP socket come back bit-identical.
TEST(Udp, ReceiverDrainsEncodedPackets) {
  UdpReceiver rx;
  std::string err;
  ASSERT_TRUE(rx.open("127.0.0.1", 0, 4 << 20, &err)) << err;
  EXPECT_GT(rx.actual_buffer_bytes(), 0);
  std::vector<double> alt(16, 0.0), az(16, 0.0);
  const SensorInfo info = make_sensor_info(alt, az, "512x10");
  Scan s;
  s.resize(16, 512);
  for (size_t i = 0; i < s.range_mm.size(); ++i) s.range_mm[i] = uint32_t(i * 13);
  std::vector<std::vector<uint8_t>> pk;
  encode_frame(s, 3, PacketFormat::from(info), pk);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(uint16_t(rx.port()));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  for (auto& p : pk) ASSERT_EQ(::sendto(fd, p.data(), p.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)), ssize_t(p.size()));
  ::close(fd);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  int got = 0;
  for (int tries = 0; tries < 200 && got < int(pk.size()); ++tries) {
    got += rx.drain([&](uint16_t, const uint8_t* d, size_t n) { fa.add_packet(d, n, out); });
    if (got < int(pk.size())) usleep(1000);
  }
  ASSERT_EQ(got, int(pk.size()));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].range_mm, s.range_mm);
}
