// A minimal MCAP writer (Header, Schema, Channel, chunks none/zstd/lz4 of Message records with their
// CRC-32, Data End with the data section's CRC-32, Footer), for tests and the import benchmark's
// generated files (ROS 1 or CDR message bytes as given). No summary section or indexes: readers that
// need them (our reader does not) rebuild them. Not a recorder.
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace fploc::rec {

class McapWriter {
 public:
  // compression: "none" (""), "zstd" or "lz4"; a chunk is closed when it holds chunk_bytes of records.
  bool open(const std::string& path, const std::string& compression = "zstd", size_t chunk_bytes = 768 * 1024);
  // Registers a topic of type `type` ("sensor_msgs/msg/LaserScan"), message encoding "ros1" or "cdr";
  // returns its channel id.
  uint16_t add_channel(const std::string& topic, const std::string& type, const std::string& encoding = "ros1");
  void write(uint16_t channel, int64_t time_ns, const uint8_t* data, size_t size);
  // Writes the last chunk, Data End and the Footer; false on an I/O error.
  bool close();
  ~McapWriter() { if (f_) close(); }
  // When set, every compressed chunk's payload is also appended here (zstd frames / LZ4 frames that
  // `zstd -dc` / `lz4 -dc` decode: the benchmark times the decompressor's tool on the same data).
  std::FILE* chunk_copy = nullptr;

 private:
  void put(const std::vector<uint8_t>& b);  // to the file, into the data section's CRC
  void flush_chunk();
  std::FILE* f_ = nullptr;
  std::string compression_;
  size_t chunk_bytes_ = 0;
  std::vector<uint8_t> chunk_;
  int64_t chunk_start_ = 0, chunk_end_ = 0;
  uint32_t seq_ = 0;
  uint16_t next_id_ = 1;
  uint32_t crc_ = 0;  // CRC-32 of everything written so far
  bool ok_ = true;
};

}  // namespace fploc::rec
