// LcmLog (own framing, buffers handed to a writer thread) writes byte for byte what lcm's
// lcm_eventlog_write_event writes, for events smaller and larger than its buffers, split in two parts, and
// with payloads written from where they are (writev; more than a batch's iovecs in a row), and encoded in place.
#include <gtest/gtest.h>
#include <lcm/eventlog.h>

#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <unistd.h>
#include <vector>

#include "lcm_log.h"

namespace {

std::vector<char> slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void same_bytes_as_lcm_eventlog(bool direct) {
  const auto dir = std::filesystem::temp_directory_path() / ("lcm_log_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string a = (dir / "ours.lcm").string(), b = (dir / "lcm.lcm").string();
  std::mt19937 rng(7);
  fploc::import::LcmLog ours;
  ASSERT_TRUE(ours.open(a, direct));
  if (direct && !ours.direct()) std::printf("(%s refuses O_DIRECT: written through the page cache)\n", dir.c_str());
  lcm_eventlog_t* ref = lcm_eventlog_create(b.c_str(), "w");
  ASSERT_NE(ref, nullptr);
  std::deque<std::vector<uint8_t>> kept;  // stable payloads: valid until close()
  const int kEvents = 2000;
  for (int i = 0; i < kEvents; ++i) {
    // Mostly packet-sized events, some larger than a 256 KiB buffer, some empty, a run of 700 tiny ones.
    const size_t n = i % 97 == 5 ? size_t(1) << 20 : (i % 50 == 3 ? 0 : (i > 1000 && i < 1700 ? 1 + rng() % 16 : 1 + rng() % 20000));
    std::vector<uint8_t>& d = kept.emplace_back(n);
    for (auto& x : d) x = uint8_t(rng());
    const std::string ch = i % 3 ? "OS1_LIDAR_PACKETS" : "OS1_IMU";
    const int64_t t = 1700000000000000 + i * 1000;
    const size_t cut = n / 3;
    if (i % 4 == 1) ASSERT_TRUE(ours.write_parts(ch, t, d.data(), cut, d.data() + cut, n - cut));
    else if (i % 4 == 3 || (i > 1000 && i < 1700)) ASSERT_TRUE(ours.write_parts(ch, t, d.data(), cut, d.data() + cut, n - cut, true));
    else if (i % 8 == 2) {  // encoded in place
      uint8_t* p = ours.begin_event(ch, t, n);
      ASSERT_NE(p, nullptr);
      if (n) std::memcpy(p, d.data(), n);
    } else ASSERT_TRUE(ours.write_raw(ch, t, d.data(), n));
    lcm_eventlog_event_t e{};
    e.timestamp = t;
    e.channellen = int32_t(ch.size());
    e.datalen = int32_t(n);
    e.channel = const_cast<char*>(ch.c_str());
    e.data = d.data();
    ASSERT_EQ(lcm_eventlog_write_event(ref, &e), 0);
  }
  EXPECT_TRUE(ours.close());
  lcm_eventlog_destroy(ref);
  EXPECT_EQ(ours.events(), uint64_t(kEvents));
  const auto x = slurp(a), y = slurp(b);
  EXPECT_GT(x.size(), size_t(4) << 20);
  EXPECT_TRUE(x == y) << "sizes " << x.size() << " vs " << y.size();
  std::filesystem::remove_all(dir);
}

TEST(LcmLog, SameBytesAsLcmEventlog) { same_bytes_as_lcm_eventlog(false); }

// O_DIRECT: aligned 4 MiB writes, the unaligned rest carried to the next buffer, the last partial block
// written through the page cache; events larger than a buffer get a larger one.
TEST(LcmLog, SameBytesAsLcmEventlogWithDirectIo) { same_bytes_as_lcm_eventlog(true); }

TEST(LcmLog, WriteToUnwritableFileFails) {
  fploc::import::LcmLog log;
  EXPECT_FALSE(log.open("/nonexistent-dir/x.lcm"));
  EXPECT_FALSE(log.write_raw("C", 0, nullptr, 0));
}

TEST(LcmLog, FullDiskIsReported) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  fploc::import::LcmLog log;
  ASSERT_TRUE(log.open("/dev/full"));
  std::vector<uint8_t> d(100000, 1);
  bool ok = true;
  for (int i = 0; i < 50 && ok; ++i) ok = log.write_parts("C", i, d.data(), 10, d.data() + 10, d.size() - 10, i % 2);
  EXPECT_FALSE(log.close() && ok);
  fploc::import::LcmLog direct;  // not a regular file: no O_DIRECT, the same error
  ASSERT_TRUE(direct.open("/dev/full", true));
  EXPECT_FALSE(direct.direct());
  ok = true;
  for (int i = 0; i < 100 && ok; ++i) ok = direct.write_parts("C", i, d.data(), 10, d.data() + 10, d.size() - 10, true);
  EXPECT_FALSE(direct.close() && ok);
}

}  // namespace
