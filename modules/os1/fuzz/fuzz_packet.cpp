// libFuzzer: lidar/IMU packet parsing and frame assembly on arbitrary bytes.
// Input: byte 0 picks beams/profile; then records of [u16 length][bytes] (length 0xFFFF = exact
// lidar packet size, so the column parser sees plenty of full-size packets).
#include <cstdint>
#include <cstring>
#include <vector>

#include "fploc/os1/packet.h"

using namespace fploc::os1;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const int kBeams[] = {16, 32, 64, 128};
  const int beams = kBeams[data[0] & 3];
  const UdpProfile profile = (data[0] & 4) ? UdpProfile::kRng19Rfl8Sig16Nir16 : UdpProfile::kLegacy;
  const char* mode = (data[0] & 8) ? "512x10" : "1024x10";
  std::vector<double> alt(size_t(beams), 0.0), az(size_t(beams), 0.0);
  SensorInfo info = make_sensor_info(alt, az, mode, profile);
  if (data[0] & 16) info.column_window_first = 100, info.column_window_last = 50;  // wrapping window
  FrameAssembler fa(info);
  const size_t full = fa.format().lidar_packet_size();
  std::vector<fploc::Scan> out;
  size_t o = 1;
  std::vector<uint8_t> pkt;
  while (o + 2 <= size) {
    uint16_t len;
    std::memcpy(&len, data + o, 2);
    o += 2;
    const size_t want = len == 0xFFFF ? full : len;
    const size_t n = std::min(want, size - o);
    pkt.assign(data + o, data + o + n);  // own buffer: ASan sees any over-read
    o += n;
    fa.add_packet(pkt.data(), pkt.size(), out);
    ImuSample s;
    parse_imu_packet(pkt.data(), pkt.size(), s);
    for (auto& sc : out) {
      if (sc.range_mm.size() != size_t(sc.height) * sc.width || sc.column_valid.size() != size_t(sc.width)) __builtin_trap();
      if (sc.missing_columns < 0 || sc.missing_columns > sc.width) __builtin_trap();
    }
    out.clear();
  }
  fa.flush(out);
  const auto& st = fa.stats();
  if (st.packets_accepted + st.wrong_size + st.stale_packets != st.packets) __builtin_trap();
  return 0;
}
