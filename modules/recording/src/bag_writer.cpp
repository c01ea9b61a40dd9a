#include "fploc/recording/bag_writer.h"

#include <cstring>

#include "fploc/recording/decompress.h"

namespace fploc::rec {
namespace {

void put32(std::vector<uint8_t>& b, uint32_t v) { b.insert(b.end(), reinterpret_cast<uint8_t*>(&v), reinterpret_cast<uint8_t*>(&v) + 4); }
void put64(std::vector<uint8_t>& b, uint64_t v) { b.insert(b.end(), reinterpret_cast<uint8_t*>(&v), reinterpret_cast<uint8_t*>(&v) + 8); }
void field(std::vector<uint8_t>& h, const std::string& name, const void* v, size_t n) {
  put32(h, uint32_t(name.size() + 1 + n));
  h.insert(h.end(), name.begin(), name.end());
  h.push_back('=');
  h.insert(h.end(), static_cast<const uint8_t*>(v), static_cast<const uint8_t*>(v) + n);
}
void field(std::vector<uint8_t>& h, const std::string& name, const std::string& v) { field(h, name, v.data(), v.size()); }
void field_op(std::vector<uint8_t>& h, uint8_t op) { field(h, "op", &op, 1); }
void time_field(std::vector<uint8_t>& h, const char* name, int64_t ns) {
  const uint32_t t[2] = {uint32_t(ns / 1000000000), uint32_t(ns % 1000000000)};
  field(h, name, t, 8);
}
void record(std::vector<uint8_t>& out, const std::vector<uint8_t>& header, const uint8_t* data, size_t n) {
  put32(out, uint32_t(header.size()));
  out.insert(out.end(), header.begin(), header.end());
  put32(out, uint32_t(n));
  out.insert(out.end(), data, data + n);
}

}  // namespace

bool BagWriter::open(const std::string& path, const std::string& compression, size_t chunk_bytes) {
  f_ = std::fopen(path.c_str(), "wb");
  if (!f_) return false;
  compression_ = compression;
  chunk_bytes_ = chunk_bytes;
  std::fwrite("#ROSBAG V2.0\n", 1, 13, f_);
  // Bag header, rewritten by close() (index position, counts), padded to 4096 B.
  std::vector<uint8_t> rec(4096 - 13, ' ');
  std::fwrite(rec.data(), 1, rec.size(), f_);
  return true;
}

uint32_t BagWriter::add_connection(const std::string& topic, const std::string& type, const std::string& md5,
                                   const std::string& definition) {
  conns_.push_back({topic, type, md5, definition});
  conn_in_file_.push_back(false);
  return uint32_t(conns_.size() - 1);
}

void BagWriter::write(uint32_t conn, int64_t t, const uint8_t* data, size_t n) {
  std::vector<uint8_t> h;
  if (!conn_in_file_[conn]) {
    conn_in_file_[conn] = true;
    const Conn& c = conns_[conn];
    field_op(h, 0x07);
    field(h, "conn", &conn, 4);
    field(h, "topic", c.topic);
    std::vector<uint8_t> d;
    field(d, "topic", c.topic);
    field(d, "type", c.type);
    field(d, "md5sum", c.md5);
    field(d, "message_definition", c.def);
    record(chunk_, h, d.data(), d.size());
    h.clear();
  }
  if (chunk_index_.empty()) chunk_start_ = t;
  chunk_start_ = std::min(chunk_start_, t);
  chunk_end_ = std::max(chunk_end_, t);
  chunk_index_[conn].push_back({t, uint32_t(chunk_.size())});
  field_op(h, 0x02);
  field(h, "conn", &conn, 4);
  time_field(h, "time", t);
  record(chunk_, h, data, n);
  if (chunk_.size() >= chunk_bytes_) flush_chunk();
}

void BagWriter::flush_chunk() {
  if (chunk_.empty()) return;
  ChunkInfo ci;
  ci.pos = uint64_t(std::ftell(f_));
  ci.start = chunk_start_;
  ci.end = chunk_end_;
  const std::vector<uint8_t> z = compress(compression_, chunk_.data(), chunk_.size());
  if (chunk_copy && compression_ != "none") ok_ = ok_ && std::fwrite(z.data(), 1, z.size(), chunk_copy) == z.size();
  std::vector<uint8_t> h, out;
  field_op(h, 0x05);
  field(h, "compression", compression_);
  const uint32_t size = uint32_t(chunk_.size());
  field(h, "size", &size, 4);
  record(out, h, z.data(), z.size());
  for (const auto& [conn, entries] : chunk_index_) {
    std::vector<uint8_t> ih, d;
    field_op(ih, 0x04);
    const uint32_t ver = 1, count = uint32_t(entries.size());
    field(ih, "ver", &ver, 4);
    field(ih, "conn", &conn, 4);
    field(ih, "count", &count, 4);
    for (const auto& [t, off] : entries) {
      put32(d, uint32_t(t / 1000000000));
      put32(d, uint32_t(t % 1000000000));
      put32(d, off);
    }
    record(out, ih, d.data(), d.size());
    ci.counts[conn] = count;
  }
  ok_ = ok_ && std::fwrite(out.data(), 1, out.size(), f_) == out.size();
  chunks_.push_back(std::move(ci));
  chunk_.clear();
  chunk_index_.clear();
}

bool BagWriter::close() {
  if (!f_) return false;
  flush_chunk();
  const uint64_t index_pos = uint64_t(std::ftell(f_));
  std::vector<uint8_t> out;
  for (uint32_t i = 0; i < conns_.size(); ++i) {
    std::vector<uint8_t> h, d;
    field_op(h, 0x07);
    field(h, "conn", &i, 4);
    field(h, "topic", conns_[i].topic);
    field(d, "topic", conns_[i].topic);
    field(d, "type", conns_[i].type);
    field(d, "md5sum", conns_[i].md5);
    field(d, "message_definition", conns_[i].def);
    record(out, h, d.data(), d.size());
  }
  for (const auto& ci : chunks_) {
    std::vector<uint8_t> h, d;
    field_op(h, 0x06);
    const uint32_t ver = 1, count = uint32_t(ci.counts.size());
    field(h, "ver", &ver, 4);
    field(h, "chunk_pos", &ci.pos, 8);
    time_field(h, "start_time", ci.start);
    time_field(h, "end_time", ci.end);
    field(h, "count", &count, 4);
    for (const auto& [c, k] : ci.counts) {
      put32(d, c);
      put32(d, k);
    }
    record(out, h, d.data(), d.size());
  }
  ok_ = ok_ && std::fwrite(out.data(), 1, out.size(), f_) == out.size();
  // Bag header at byte 13: index_pos, conn_count, chunk_count; data pads the record to 4096 B.
  std::vector<uint8_t> h, rec;
  field_op(h, 0x03);
  field(h, "index_pos", &index_pos, 8);
  const uint32_t nc = uint32_t(conns_.size()), nk = uint32_t(chunks_.size());
  field(h, "conn_count", &nc, 4);
  field(h, "chunk_count", &nk, 4);
  const size_t pad = 4096 - 13 - 4 - h.size() - 4;
  std::vector<uint8_t> spaces(pad, ' ');
  record(rec, h, spaces.data(), spaces.size());
  std::fseek(f_, 13, SEEK_SET);
  ok_ = ok_ && std::fwrite(rec.data(), 1, rec.size(), f_) == rec.size();
  ok_ = std::fclose(f_) == 0 && ok_;
  f_ = nullptr;
  return ok_;
}

}  // namespace fploc::rec
