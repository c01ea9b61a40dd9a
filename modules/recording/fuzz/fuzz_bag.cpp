// libFuzzer: ROS 1 bag reader + all message decoders. Inputs without the bag magic get it prepended,
// so mutations spend their time on records (seeds: real and written bags).
#include <cstring>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char kMagic[] = "#ROSBAG V2.0\n";
  if (size >= 13 && std::memcmp(data, kMagic, 13) == 0) {
    fuzz_recording(data, size);
  } else {
    std::vector<uint8_t> b(kMagic, kMagic + 13);
    b.insert(b.end(), data, data + size);
    fuzz_recording(b.data(), b.size());
  }
  return 0;
}
