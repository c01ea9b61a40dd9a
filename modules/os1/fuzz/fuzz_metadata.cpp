// libFuzzer: metadata JSON parsing; every failure must be a MetadataError, never a crash, and a parsed
// SensorInfo must be self-consistent enough to build a FrameAssembler and XYZ table.
#include <cstdint>
#include <string>

#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"

using namespace fploc::os1;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    SensorInfo info = parse_metadata(text, "fuzz.json");
    if (info.beams.beams() != info.pixels_per_column) __builtin_trap();
    if (int(info.beams.pixel_shift_by_row.size()) != info.pixels_per_column) __builtin_trap();
    if (info.pixels_per_column <= 64 && info.columns_per_packet <= 16) {
      FrameAssembler fa(info);
      std::vector<uint8_t> pkt(fa.format().lidar_packet_size(), 0xFF);
      std::vector<fploc::Scan> out;
      fa.add_packet(pkt.data(), pkt.size(), out);
      fa.flush(out);
    }
  } catch (const MetadataError&) {
  }
  return 0;
}
