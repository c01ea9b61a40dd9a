// Decode + XYZ of one 1024x64 frame (64 legacy packets), the driver's per-frame work.
#include <benchmark/benchmark.h>

#include <cstring>

#include "fploc/core/xyz.h"
#include "fploc/os1/packet.h"

using namespace fploc;
using namespace fploc::os1;

namespace {
struct Fixture {
  SensorInfo info;
  std::vector<std::vector<uint8_t>> packets;
  Fixture() {
    std::vector<double> alt, az;
    for (int i = 0; i < 64; ++i) {
      alt.push_back(16.6 - 33.2 * i / 63.0);
      az.push_back(i % 4 == 0 ? 3.1 : i % 4 == 1 ? 0.9 : i % 4 == 2 ? -1.3 : -3.1);
    }
    info = make_sensor_info(alt, az);
    Scan s;
    s.resize(64, 1024);
    for (size_t i = 0; i < s.range_mm.size(); ++i) s.range_mm[i] = i % 7 == 0 ? 0 : uint32_t(1000 + (i * 37) % 40000);
    encode_frame(s, 1, PacketFormat::from(info), packets);
  }
};
Fixture& fixture() {
  static Fixture f;
  return f;
}
}  // namespace

static void BM_Decode(benchmark::State& st) {
  auto& fx = fixture();
  FrameAssembler fa(fx.info);
  std::vector<Scan> out;
  uint16_t fid = 0;
  for (auto _ : st) {
    out.clear();
    ++fid;
    for (auto& p : fx.packets) {  // rewrite frame ids so every iteration is a new frame
      for (int c = 0; c < 16; ++c) std::memcpy(p.data() + c * 788 + 10, &fid, 2);
      fa.add_packet(p.data(), p.size(), out);
    }
    benchmark::DoNotOptimize(out.data());
    if (!out.empty()) fa.recycle(std::move(out.back()));
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_Decode)->Unit(benchmark::kMicrosecond);

static void BM_DecodeAndXyz(benchmark::State& st) {
  auto& fx = fixture();
  FrameAssembler fa(fx.info);
  const XyzLut lut = make_xyz_lut(fx.info.beams, fx.info.columns_per_frame);
  std::vector<Scan> out;
  std::vector<Eigen::Vector3f> xyz;
  uint16_t fid = 0;
  for (auto _ : st) {
    out.clear();
    ++fid;
    for (auto& p : fx.packets) {
      for (int c = 0; c < 16; ++c) std::memcpy(p.data() + c * 788 + 10, &fid, 2);
      fa.add_packet(p.data(), p.size(), out);
    }
    scan_to_xyz(out.back(), lut, xyz);
    benchmark::DoNotOptimize(xyz.data());
    fa.recycle(std::move(out.back()));
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_DecodeAndXyz)->Unit(benchmark::kMicrosecond);

static void BM_Encode(benchmark::State& st) {
  auto& fx = fixture();
  Scan s;
  s.resize(64, 1024);
  std::vector<std::vector<uint8_t>> pk;
  for (auto _ : st) {
    encode_frame(s, 1, PacketFormat::from(fx.info), pk);
    benchmark::DoNotOptimize(pk.data());
  }
}
BENCHMARK(BM_Encode)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
