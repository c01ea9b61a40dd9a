// The driver's whole per-frame path without the socket: 64 legacy packets -> FrameAssembler -> scan_t
// (to_msg) -> LCM encoding, for one 1024x64 frame.
#include <benchmark/benchmark.h>
#include <fploc/scan_t.hpp>

#include <cstring>

#include "fploc/adapters/scan_t.h"
#include "fploc/os1/packet.h"

using namespace fploc;
using namespace fploc::os1;

static void BM_DriverFrame(benchmark::State& st) {
  std::vector<double> alt, az;
  for (int i = 0; i < 64; ++i) alt.push_back(16.6 - 33.2 * i / 63.0), az.push_back(i % 2 ? 1.0 : -1.0);
  const SensorInfo info = make_sensor_info(alt, az);
  Scan s;
  s.resize(64, 1024);
  for (size_t i = 0; i < s.range_mm.size(); ++i) s.range_mm[i] = i % 7 == 0 ? 0 : uint32_t(1000 + (i * 37) % 40000);
  std::vector<std::vector<uint8_t>> packets;
  encode_frame(s, 1, PacketFormat::from(info), packets);
  FrameAssembler fa(info);
  std::vector<Scan> out;
  scan_t msg;
  std::vector<uint8_t> buf;
  uint16_t fid = 0;
  for (auto _ : st) {
    out.clear();
    ++fid;
    for (auto& p : packets) {
      for (int c = 0; c < 16; ++c) std::memcpy(p.data() + c * 788 + 10, &fid, 2);
      fa.add_packet(p.data(), p.size(), out);
    }
    fploc::adapters::to_msg(out.back(), msg);
    buf.resize(size_t(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, int(buf.size()));
    benchmark::DoNotOptimize(buf.data());
    fa.recycle(std::move(out.back()));
  }
  st.counters["msg_bytes"] = double(buf.size());
}
BENCHMARK(BM_DriverFrame)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
