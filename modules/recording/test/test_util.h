#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
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
}  // namespace fploc::rec::test
