// Conformance with the Ouster SDK: the RANGE field of our Scan hashes to the SDK's digest
// (OS-1-32-G_v2.1.1_1024x10_digest.json, FieldDigest.from_scan: md5 of the staggered uint32 image).
#include <gtest/gtest.h>
#include <openssl/evp.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "fploc/os1/packet.h"
#include "fploc/os1/pcap.h"
#include "test_util.h"

using namespace fploc;
using namespace fploc::os1;
using fploc::os1::test::ouster_dir;

static std::string md5_hex(const void* p, size_t n) {
  unsigned char d[EVP_MAX_MD_SIZE];
  unsigned len = 0;
  EVP_Digest(p, n, d, &len, EVP_md5(), nullptr);
  std::string s;
  static const char* k = "0123456789abcdef";
  for (unsigned i = 0; i < len; ++i) s += k[d[i] >> 4], s += k[d[i] & 15];
  return s;
}

TEST(SdkDigest, RangeSignalReflectivityMatch) {
  FPLOC_REQUIRE_SHARED();
  const std::string base = ouster_dir() + "/OS-1-32-G_v2.1.1_1024x10";
  const SensorInfo info = load_metadata(base + ".json");
  nlohmann::json ref;
  std::ifstream(base + "_digest.json") >> ref;
  PcapReader r;
  ASSERT_TRUE(r.open(base + ".pcap")) << r.error();
  FrameAssembler fa(info);
  std::vector<Scan> frames;
  UdpDatagram d;
  while (r.next(d)) fa.add_packet(d.data, d.size, frames);
  fa.flush(frames);
  ASSERT_EQ(frames.size(), ref["scans"].size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const Scan& s = frames[i];
    const auto& h = ref["scans"][i];
    EXPECT_EQ(std::to_string(s.frame_id), h["FRAME_ID"].get<std::string>());
    EXPECT_EQ(md5_hex(s.range_mm.data(), s.range_mm.size() * 4), h["RANGE"].get<std::string>());
    EXPECT_EQ(md5_hex(s.signal.data(), s.signal.size() * 2), h["SIGNAL"].get<std::string>());
    EXPECT_EQ(md5_hex(s.reflectivity.data(), s.reflectivity.size()), h["REFLECTIVITY"].get<std::string>());
    std::vector<uint16_t> mid(s.measurement_id.begin(), s.measurement_id.end());
    EXPECT_EQ(md5_hex(mid.data(), mid.size() * 2), h["MEASUREMENT_ID"].get<std::string>());
  }
}
