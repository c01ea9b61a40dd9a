#pragma once
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "fploc/recording/recording.h"

namespace fploc::rec::test {
inline std::string data_dir() { return std::string(FPLOC_SHARED_DIR) + "/data"; }
#define FPLOC_REQUIRE_FILE(p) \
  if (!std::filesystem::exists(p)) GTEST_SKIP() << "no " << (p) << " (../shared/data absent)"

inline std::vector<uint8_t> slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), {});
}

struct Msg {
  std::string topic;
  int64_t t;
  std::vector<uint8_t> data;
};
// Every message of a recording in memory (copies), and the reader's error.
inline std::vector<Msg> read_all(const uint8_t* d, size_t n, std::string* error, std::string name = "mem") {
  std::string err;
  auto r = open_recording_memory(d, n, name, &err);
  std::vector<Msg> out;
  if (!r) {
    *error = err;
    return out;
  }
  RawMessage m;
  while (r->next(m)) out.push_back({r->connections().at(m.conn).topic, m.time_ns, std::vector<uint8_t>(m.data, m.data + m.size)});
  *error = r->error();
  return out;
}

// The mixed-topic test recording of the bag and MCAP tests: message i on "/a" (i % 3 != 0) or "/b", at
// 100 s + i ms, a ROS uint8[] (4-byte length, then 0..49 letters that depend on i and `stride`).
constexpr int kMixedMessages = 300;
inline int64_t mixed_time_ns(int i) { return 1000000000LL * 100 + i * 1000000LL; }
inline std::vector<uint8_t> mixed_payload(int i, int stride) {
  std::vector<uint8_t> d(4 + size_t(i % 50));
  const uint32_t len = uint32_t(d.size() - 4);
  std::memcpy(d.data(), &len, 4);
  for (size_t k = 4; k < d.size(); ++k) d[k] = uint8_t('a' + (size_t(i * stride) + k) % 26);
  return d;
}
// Writes the mixed recording with writer W (BagWriter, McapWriter: open/write/close) and `compression`;
// `add_topics(w)` adds "/a" and "/b" and returns their ids. Returns the file's bytes.
template <class W, class AddTopics>
std::vector<uint8_t> write_mixed(const std::string& path, const std::string& compression, int stride, AddTopics add_topics) {
  {
    W w;
    EXPECT_TRUE(w.open(path, compression, 4000)) << path;
    const auto [a, b] = add_topics(w);
    for (int i = 0; i < kMixedMessages; ++i) {
      const auto d = mixed_payload(i, stride);
      w.write(i % 3 ? a : b, mixed_time_ns(i), d.data(), d.size());
    }
    EXPECT_TRUE(w.close()) << path;
  }
  return slurp(path);
}
// Every message of the mixed recording read back in order, with its topic, time and size.
inline void expect_mixed(const std::vector<Msg>& msgs, const std::string& what) {
  ASSERT_EQ(msgs.size(), size_t(kMixedMessages)) << what;
  for (int i = 0; i < kMixedMessages; ++i) {
    EXPECT_EQ(msgs[i].topic, i % 3 ? "/a" : "/b") << what;
    EXPECT_EQ(msgs[i].t, mixed_time_ns(i)) << what;
    EXPECT_EQ(msgs[i].data.size(), 4u + size_t(i % 50)) << what;
  }
}
}  // namespace fploc::rec::test
