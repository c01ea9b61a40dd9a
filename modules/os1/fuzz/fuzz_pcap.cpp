// libFuzzer: the pcap path (libpcap on a memory file -> link layer -> IPv4 reassembly -> UDP -> Ouster
// packets). Byte 0 picks the beam count; the rest is the "file". A second pass feeds the same bytes as
// single link-layer frames straight into decode_frame (all link types), so the decoder is fuzzed even
// when libpcap rejects the file header.
#include <cstdint>
#include <vector>

#include "fploc/os1/packet.h"
#include "fploc/os1/pcap.h"

using namespace fploc::os1;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const int beams = (data[0] & 1) ? 64 : 16;
  std::vector<double> alt(size_t(beams), 1.0), az(size_t(beams), 0.0);
  const SensorInfo info = make_sensor_info(alt, az);
  FrameAssembler fa(info);
  PacketClassifier cls{0, 0, fa.format().lidar_packet_size()};
  std::vector<fploc::Scan> out;
  std::vector<uint8_t> file(data + 1, data + size);
  PcapReader r;
  if (r.open_memory(file.data(), file.size())) {
    UdpDatagram d;
    int guard = 0;
    while (r.next(d) && ++guard < 100000) {
      if (cls.classify(d.dst_port, d.size) == PacketKind::kLidar) fa.add_packet(d.data, d.size, out);
      ImuSample s;
      parse_imu_packet(d.data, d.size, s);
      out.clear();
    }
  }
  static const int kDlt[] = {0, 1, 12, 14, 101, 108, 113, 228, 276};
  Ipv4Reassembler ra(4);
  std::vector<uint8_t> scratch;
  PcapStats st;
  // Split into frames of length given by each leading byte pair.
  size_t o = 1;
  int k = 0;
  while (o + 2 < size) {
    const size_t len = std::min<size_t>(size - o - 2, size_t(data[o]) << 4 | (data[o + 1] & 15));
    std::vector<uint8_t> frame(data + o + 2, data + o + 2 + len);
    UdpDatagram d;
    const size_t orig = (data[o + 1] & 0x80) ? len + 1 : len;  // sometimes claim truncation
    if (decode_frame(kDlt[(k++ + data[0]) % 9], frame.data(), frame.size(), orig, int64_t(o) * 1000, ra, scratch, d, st)) {
      if (d.size > 65535) __builtin_trap();
      volatile uint8_t sink = d.size ? d.data[d.size - 1] : 0;  // must be readable
      (void)sink;
    }
    o += 2 + len;
  }
  return 0;
}
