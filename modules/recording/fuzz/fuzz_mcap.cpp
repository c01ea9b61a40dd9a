// libFuzzer: MCAP reader + all message decoders. Inputs without the MCAP magic get it prepended (seeds:
// small files from tests/import/write_mcap.js, chunks none/zstd/lz4 and unchunked).
#include <cstring>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  if (size >= 8 && std::memcmp(data, kMagic, 8) == 0) {
    fuzz_recording(data, size);
  } else {
    std::vector<uint8_t> b(kMagic, kMagic + 8);
    b.insert(b.end(), data, data + size);
    fuzz_recording(b.data(), b.size());
  }
  return 0;
}
