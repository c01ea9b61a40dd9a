#include "fploc/recording/mcap_writer.h"

#include <isa-l/crc.h>

#include <cstring>

#include "fploc/recording/decompress.h"

namespace fploc::rec {
namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

template <class T>
void le(std::vector<uint8_t>& b, T v) {
  uint8_t x[sizeof(T)];
  std::memcpy(x, &v, sizeof v);
  b.insert(b.end(), x, x + sizeof(T));
}
void str(std::vector<uint8_t>& b, const std::string& s) {
  le<uint32_t>(b, uint32_t(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}
// op, u64 length, body.
std::vector<uint8_t> record(uint8_t op, const std::vector<uint8_t>& body) {
  std::vector<uint8_t> r{op};
  le<uint64_t>(r, body.size());
  r.insert(r.end(), body.begin(), body.end());
  return r;
}
uint32_t crc_of(const uint8_t* p, size_t n, uint32_t c = 0) { return crc32_gzip_refl(c, p, n); }

}  // namespace

void McapWriter::put(const std::vector<uint8_t>& b) {
  if (b.empty()) return;
  crc_ = crc_of(b.data(), b.size(), crc_);
  ok_ = ok_ && std::fwrite(b.data(), 1, b.size(), f_) == b.size();
}

bool McapWriter::open(const std::string& path, const std::string& compression, size_t chunk_bytes) {
  f_ = std::fopen(path.c_str(), "wb");
  if (!f_) return false;
  compression_ = compression == "none" ? "" : compression;
  chunk_bytes_ = chunk_bytes;
  crc_ = 0;
  put(std::vector<uint8_t>(kMagic, kMagic + 8));
  std::vector<uint8_t> h;
  str(h, "ros1");  // profile
  str(h, "fploc McapWriter");
  put(record(0x01, h));
  return true;
}

uint16_t McapWriter::add_channel(const std::string& topic, const std::string& type, const std::string& encoding) {
  const uint16_t id = next_id_++;
  std::vector<uint8_t> s;  // Schema: id, name, encoding, data
  le<uint16_t>(s, id);
  str(s, type);
  str(s, encoding == "cdr" ? "ros2msg" : "ros1msg");
  str(s, "");
  put(record(0x03, s));
  std::vector<uint8_t> c;  // Channel: id, schema id, topic, message encoding, metadata (empty map)
  le<uint16_t>(c, id);
  le<uint16_t>(c, id);
  str(c, topic);
  str(c, encoding);
  le<uint32_t>(c, 0);
  put(record(0x04, c));
  return id;
}

void McapWriter::write(uint16_t channel, int64_t time_ns, const uint8_t* data, size_t size) {
  if (chunk_.empty()) chunk_start_ = time_ns;
  chunk_end_ = time_ns;
  chunk_.push_back(0x05);
  le<uint64_t>(chunk_, 2 + 4 + 8 + 8 + size);
  le<uint16_t>(chunk_, channel);
  le<uint32_t>(chunk_, seq_++);
  le<uint64_t>(chunk_, uint64_t(time_ns));
  le<uint64_t>(chunk_, uint64_t(time_ns));
  chunk_.insert(chunk_.end(), data, data + size);
  if (chunk_.size() >= chunk_bytes_) flush_chunk();
}

void McapWriter::flush_chunk() {
  if (chunk_.empty()) return;
  const std::vector<uint8_t> z = compression_.empty() ? chunk_ : compress(compression_, chunk_.data(), chunk_.size());
  if (z.empty()) ok_ = false;
  if (chunk_copy && !compression_.empty()) ok_ = ok_ && std::fwrite(z.data(), 1, z.size(), chunk_copy) == z.size();
  std::vector<uint8_t> b;  // Chunk: start, end, uncompressed size, uncompressed CRC, compression, records
  le<uint64_t>(b, uint64_t(chunk_start_));
  le<uint64_t>(b, uint64_t(chunk_end_));
  le<uint64_t>(b, chunk_.size());
  le<uint32_t>(b, crc_of(chunk_.data(), chunk_.size()));
  str(b, compression_);
  le<uint64_t>(b, z.size());
  b.insert(b.end(), z.begin(), z.end());
  put(record(0x06, b));
  chunk_.clear();
}

bool McapWriter::close() {
  if (!f_) return false;
  flush_chunk();
  std::vector<uint8_t> e;
  le<uint32_t>(e, uint32_t(crc_));  // Data End: CRC of everything before it
  const auto de = record(0x0F, e);
  ok_ = ok_ && std::fwrite(de.data(), 1, de.size(), f_) == de.size();
  std::vector<uint8_t> ft;  // Footer: no summary
  le<uint64_t>(ft, 0);
  le<uint64_t>(ft, 0);
  le<uint32_t>(ft, 0);
  const auto fr = record(0x02, ft);
  ok_ = ok_ && std::fwrite(fr.data(), 1, fr.size(), f_) == fr.size();
  ok_ = ok_ && std::fwrite(kMagic, 1, 8, f_) == 8;
  ok_ = std::fclose(f_) == 0 && ok_;
  f_ = nullptr;
  return ok_;
}

}  // namespace fploc::rec
