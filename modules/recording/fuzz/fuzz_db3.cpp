// libFuzzer: the rosbag2 sqlite3 (.db3) reader (libsqlite3 over the input, sqlite3_deserialize read-only) + all
// message decoders. Inputs without the SQLite magic get it in place of their first 16 bytes (seeds: small .db3 files
// from tests/import/mcap_to_db3.py of write_mcap.js's "small" MCAP).
#include <cstring>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char kMagic[16] = "SQLite format 3";  // (and its NUL)
  std::vector<uint8_t> b(data, data + size);
  if (b.size() < 16) b.resize(16);
  std::memcpy(b.data(), kMagic, 16);
  fuzz_recording(b.data(), b.size());
  return 0;
}
