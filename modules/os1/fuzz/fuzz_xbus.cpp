// libFuzzer: Xsens Xbus framing + MTData2 parsing on arbitrary serial bytes (fed in odd-sized chunks).
#include <cmath>
#include <cstdint>

#include "fploc/os1/xsens.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fploc::os1::XbusParser p;
  const size_t chunk = size ? (data[0] % 13) + 1 : 1;
  for (size_t o = 0; o < size; o += chunk)
    p.feed(data + o, std::min(chunk, size - o), [](const fploc::os1::XsensSample& s) {
      for (double v : s.accel)
        if (!std::isfinite(v)) __builtin_trap();
    });
  fploc::os1::XsensSample s;
  fploc::os1::parse_mtdata2(data, size, s);
  return 0;
}
