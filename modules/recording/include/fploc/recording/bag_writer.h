// A minimal ROS 1 bag 2.0 writer (chunks none/bz2/lz4, connection + message records, index data, chunk
// info and the index section), for tests and the import benchmark's generated files. Not a recorder.
#pragma once
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace fploc::rec {

class BagWriter {
 public:
  // compression: "none", "bz2" or "lz4"; a chunk is closed when it holds chunk_bytes.
  bool open(const std::string& path, const std::string& compression = "none", size_t chunk_bytes = 768 * 1024);
  // Registers a topic; returns its connection id.
  uint32_t add_connection(const std::string& topic, const std::string& type, const std::string& md5 = "*",
                          const std::string& definition = "");
  void write(uint32_t conn, int64_t time_ns, const uint8_t* data, size_t size);
  // Writes the last chunk and the index; false on an I/O error.
  bool close();
  ~BagWriter() { if (f_) close(); }
  // When set, every compressed chunk's payload is also appended here: a concatenation of bz2 streams or
  // LZ4 frames that `bzip2 -dc` / `lz4 -dc` decode (the benchmark times the decompressor's own tool on
  // the same data).
  std::FILE* chunk_copy = nullptr;

 private:
  struct Conn { std::string topic, type, md5, def; };
  void flush_chunk();
  std::FILE* f_ = nullptr;
  std::string compression_;
  size_t chunk_bytes_ = 0;
  std::vector<Conn> conns_;
  std::vector<uint8_t> chunk_;
  std::map<uint32_t, std::vector<std::pair<int64_t, uint32_t>>> chunk_index_;  // conn -> (time, offset)
  std::vector<bool> conn_in_file_;
  int64_t chunk_start_ = 0, chunk_end_ = 0;
  struct ChunkInfo { uint64_t pos; int64_t start, end; std::map<uint32_t, uint32_t> counts; };
  std::vector<ChunkInfo> chunks_;
  bool ok_ = true;
};

}  // namespace fploc::rec
