// LogReader: a whole log, one cut short, one whose event length field is damaged (liblcm alone reads 2 GB into a null
// pointer there), one with a damaged channel length, and a file that is no LCM log.
#include "fploc/runtime/log_reader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

std::string scratch(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("fploc_log_reader_" + std::to_string(getpid()) + "_" + name)).string();
}

// Three events with 10, 20 and 30 data bytes on channel "CH"; each event is 28 + 2 + n bytes.
std::vector<char> three_events() {
  const std::string p = scratch("three.lcm");
  {
    lcm::LogFile w(p, "w");
    for (int n : {10, 20, 30}) {
      std::vector<uint8_t> data(static_cast<size_t>(n), static_cast<uint8_t>(n));
      lcm::LogEvent ev;
      ev.eventnum = 0;
      ev.timestamp = n;
      ev.channel = "CH";
      ev.datalen = n;
      ev.data = data.data();
      w.writeEvent(&ev);
    }
  }
  std::ifstream in(p, std::ios::binary);
  std::vector<char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::remove(p.c_str());
  return b;
}

std::string write(const std::string& name, const std::vector<char>& bytes) {
  const std::string p = scratch(name);
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return p;
}

// Reads to the end: the data lengths of the events read.
std::vector<int> read_all(fploc::rt::LogReader& r) {
  std::vector<int> lens;
  while (const lcm::LogEvent* ev = r.next()) lens.push_back(ev->datalen);
  return lens;
}

void put_be32(std::vector<char>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + size_t(i)] = char(v >> (24 - 8 * i));
}

constexpr size_t kEvent1 = 28 + 2 + 10, kEvent2 = 28 + 2 + 20;

TEST(LogReader, AWholeLogHasNoProblem) {
  const auto b = three_events();
  ASSERT_EQ(b.size(), kEvent1 + kEvent2 + 28 + 2 + 30);
  const std::string p = write("whole.lcm", b);
  fploc::rt::LogReader r(p);
  ASSERT_TRUE(r.good());
  EXPECT_EQ(read_all(r), (std::vector<int>{10, 20, 30}));
  EXPECT_EQ(r.events(), 3);
  EXPECT_EQ(r.problem(), "");
  std::remove(p.c_str());
}

TEST(LogReader, ALogCutInAnEventKeepsTheEventsBefore) {
  auto b = three_events();
  b.resize(kEvent1 + kEvent2 + 28 + 2 + 5);  // the third event's data cut
  const std::string p = write("cut.lcm", b);
  fploc::rt::LogReader r(p);
  EXPECT_EQ(read_all(r), (std::vector<int>{10, 20}));
  EXPECT_NE(r.problem().find(": event 3 at byte " + std::to_string(kEvent1 + kEvent2) + ": its data length 30 runs past the end"),
            std::string::npos) << r.problem();
  std::remove(p.c_str());
}

TEST(LogReader, ADamagedDataLengthEndsTheReadingWithItsOffset) {
  auto b = three_events();
  put_be32(b, kEvent1 + 24, 0x7fffffffu);  // the second event's data length
  const std::string p = write("datalen.lcm", b);
  fploc::rt::LogReader r(p);
  EXPECT_EQ(read_all(r), (std::vector<int>{10}));
  EXPECT_EQ(r.problem(), p + ": event 2 at byte " + std::to_string(kEvent1) + ": its data length 2147483647 runs past the end of the file (" +
                             std::to_string(b.size()) + " B: truncated, or the length damaged); the 1 events before it were read");
  put_be32(b, kEvent1 + 24, 0x80000000u);  // negative
  const std::string q = write("datalen_neg.lcm", b);
  fploc::rt::LogReader s(q);
  EXPECT_EQ(read_all(s), (std::vector<int>{10}));
  EXPECT_NE(s.problem().find("its data length -2147483648 runs past"), std::string::npos) << s.problem();
  std::remove(p.c_str());
  std::remove(q.c_str());
}

TEST(LogReader, ADamagedChannelLengthIsNamed) {
  auto b = three_events();
  put_be32(b, 20, 5000);  // the first event's channel length
  const std::string p = write("chanlen.lcm", b);
  fploc::rt::LogReader r(p);
  EXPECT_TRUE(read_all(r).empty());
  EXPECT_NE(r.problem().find(": event 1 at byte 0: its channel length 5000 is not one (1 .. 999); the 0 events before"),
            std::string::npos) << r.problem();
  std::remove(p.c_str());
}

TEST(LogReader, AFileThatIsNoLogIsSaidSo) {
  const std::string p = write("text.lcm", std::vector<char>(100, 'x'));
  fploc::rt::LogReader r(p);
  EXPECT_TRUE(read_all(r).empty());
  EXPECT_NE(r.problem().find("no LCM event in its 100 B (not an LCM event log"), std::string::npos) << r.problem();
  std::remove(p.c_str());
}

}  // namespace
