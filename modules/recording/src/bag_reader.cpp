// ROS 1 bag 2.0: "#ROSBAG V2.0\n", then records: u32 header_len, header (fields: u32 len, "name=value"),
// u32 data_len, data. op: 0x02 message data, 0x03 bag header, 0x04 index data, 0x05 chunk, 0x06 chunk
// info, 0x07 connection. Chunks hold connection and message records; their "size" field is the
// uncompressed size.
#include <algorithm>
#include <cstring>
#include <string_view>

#include "readers.h"
#include "fploc/recording/decompress.h"

namespace fploc::rec {
namespace {
using bag::Field;
using bag::Record;

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicLen = 13;

// Splits a header (or a connection record's data) into fields; false with *why when malformed.
bool parse_fields(const uint8_t* p, size_t n, std::vector<Field>& out, std::string* why) {
  out.clear();
  size_t i = 0;
  while (i < n) {
    if (n - i < 4) return *why = "header field length cut at " + std::to_string(i), false;
    const uint32_t len = rd<uint32_t>(p + i);
    i += 4;
    if (len > n - i) return *why = "header field of " + std::to_string(len) + " B overruns the header", false;
    const auto* f = reinterpret_cast<const char*>(p + i);
    const void* eq = std::memchr(f, '=', len);
    if (!eq) return *why = "header field without '='", false;
    const size_t k = size_t(static_cast<const char*>(eq) - f);
    out.push_back({std::string_view(f, k), p + i + k + 1, len - k - 1});
    i += len;
  }
  return true;
}

const Field* find(const std::vector<Field>& fs, std::string_view name) {
  for (const auto& f : fs)
    if (f.name == name) return &f;
  return nullptr;
}

// One record at base[pos]; advances pos. `end`: what base[n] is the end of ("the chunk", "the file"); *cut: set
// when the record fails only because it runs past that end (a length past it, or cut off by it).
bool read_record(const uint8_t* base, size_t n, size_t& pos, Record& r, std::string* why, const char* end = "the chunk",
                 bool* cut = nullptr) {
  if (cut) *cut = true;
  if (n - pos < 4) return *why = std::string("header length cut off by the end of ") + end, false;
  const uint32_t hl = rd<uint32_t>(base + pos);
  if (hl > n - pos - 4) return *why = "header of " + std::to_string(hl) + " B runs past the end of " + end, false;
  if (cut) *cut = false;
  if (!parse_fields(base + pos + 4, hl, r.fields, why)) return false;
  if (cut) *cut = true;
  const size_t dpos = pos + 4 + hl;
  if (n - dpos < 4) return *why = std::string("data length cut off by the end of ") + end, false;
  const uint32_t dl = rd<uint32_t>(base + dpos);
  if (dl > n - dpos - 4) return *why = "data of " + std::to_string(dl) + " B runs past the end of " + end, false;
  if (cut) *cut = false;
  const Field* op = find(r.fields, "op");
  if (!op || op->n != 1) return *why = "record without a one-byte 'op' field", false;
  r.op = op->v[0];
  r.data = base + dpos + 4;
  r.data_len = dl;
  pos = dpos + 4 + dl;
  return true;
}

// The record at byte `at` of the file, as read_record reads it, through the sequential reads
// (f.seq()): each part is read once the length before it has been checked against the end of the file,
// so a bad length fails the same check, with the same message, without reading further. *p: the
// record's first byte (valid until the next seq()).
bool read_file_record(FileBytes& f, size_t at, size_t& pos, Record& r, const uint8_t** p, std::string* why, bool* cut) {
  const size_t rem = f.size() - at;
  size_t need = std::min<size_t>(rem, 4);
  if (!(*p = f.seq(at, need))) return *why = f.read_error(), false;
  if (rem >= 4) {
    const uint32_t hl = rd<uint32_t>(*p);
    if (hl <= rem - 4) {
      need = std::min(rem, size_t(hl) + 8);
      if (!(*p = f.seq(at, need))) return *why = f.read_error(), false;
      const uint32_t dl = need == size_t(hl) + 8 ? rd<uint32_t>(*p + 4 + hl) : 0;
      if (dl <= rem - need) need += dl;
    }
  }
  if (!(*p = f.seq(at, need))) return *why = f.read_error(), false;
  size_t end = 0;
  if (!read_record(*p, rem, end, r, why, "the file", cut)) return false;
  pos = at + end;
  return true;
}

bool field_u32(const Record& r, std::string_view name, uint32_t& v, std::string* why) {
  const Field* f = find(r.fields, name);
  if (!f || f->n != 4) return *why = "op " + std::to_string(r.op) + " record without a 4-byte '" + std::string(name) + "'", false;
  v = rd<uint32_t>(f->v);
  return true;
}

std::string text(const Field* f) { return f ? std::string(reinterpret_cast<const char*>(f->v), f->n) : std::string(); }

// The next compressed chunk record at or after pos (index data and chunk info records skipped; a
// message or connection record outside chunks, a bad record or the end: none).
bool next_compressed_chunk(const uint8_t* base, size_t n, size_t pos, size_t& at, Record& r) {
  std::string why;
  for (int k = 0; k < 256 && pos < n; ++k) {  // (a record cut by the end of the file: none)
    at = pos;
    if (!read_record(base, n, pos, r, &why)) return false;
    if (r.op == 0x05) {
      const Field* c = find(r.fields, "compression");
      return c && text(c) != "none";
    }
    if (r.op == 0x02 || r.op == 0x07) return false;
  }
  return false;
}

}  // namespace

void BagReader::prefetch_after(size_t pos) {
  if (ahead_.pending()) return;
  size_t at = 0;
  Record r;
  if (!next_compressed_chunk(f_->data(), size_, pos, at, r)) return;
  uint32_t usize = 0;
  std::string why;
  if (!field_u32(r, "size", usize, &why)) return;  // reported when the chunk is reached
  ahead_.start({at, text(find(r.fields, "compression")), r.data, r.data_len, usize, false});
}

std::string BagReader::cut_cause(size_t at) const {
  if (index_pos_ > size_)
    return "file truncated: the bag header puts its index at byte " + std::to_string(index_pos_);
  if (index_pos_ > at)  // the index is in the file, after this record: the file is not short, the length is wrong
    return "the file is not short (its index at byte " + std::to_string(index_pos_) + " is in it): the length is damaged";
  return "file truncated?";
}

// The record at `at` runs past the end of the file (why): the error, with the file's size and what that
// means; or, for an uncompressed chunk, "" after setting it up as the chunk being read: its records up to the
// cut are whole and are read first (then cut_error_).
std::string BagReader::cut_record(size_t at, const std::string& why) {
  const size_t rem = size_ - at;
  const std::string size = "(file size " + std::to_string(size_) + " B; " + cut_cause(at) + ")";
  const std::string plain = "record at byte " + std::to_string(at) + ": " + why + " " + size;
  const uint8_t* p = rem >= 8 ? f_->seq(at, rem) : nullptr;
  if (!p) return plain;
  const uint32_t hl = rd<uint32_t>(p);
  Record& r = rec_;
  std::string w;
  if (hl > rem - 8 || !parse_fields(p + 4, hl, r.fields, &w)) return plain;
  const Field* op = find(r.fields, "op");
  const Field* c = find(r.fields, "compression");
  if (!op || op->n != 1 || op->v[0] != 0x05 || !c) return plain;
  const std::string method = text(c);
  const uint32_t dl = rd<uint32_t>(p + 4 + hl);
  const std::string what = "record at byte " + std::to_string(at) + ": chunk (" + escaped(method) + ") of " + std::to_string(dl) +
                           " B runs past the end of the file " + size;
  if (method != "none") return what + ": a cut compressed chunk cannot be decompressed, its messages are lost";
  cut_error_ = what;
  cd_ = p + 8 + hl;
  cn_ = rem - 8 - hl;
  cpos_ = 0;
  chunk_at_ = at;
  top_level_ = false;
  chunk_what_ = "chunk at byte " + std::to_string(at) + " (none)";
  pos_ = size_;
  return "";
}

BagReader::BagReader(std::unique_ptr<FileBytes> f, std::string name) : FileReader(std::move(f), std::move(name), "bag 2.0") {
  if (size_ < kMagicLen || std::memcmp(f_->data(), kMagic, kMagicLen) != 0) {
    stop("not a ROS bag 2.0 (no '#ROSBAG V2.0' magic)");
    return;
  }
  pos_ = kMagicLen;
}

bool BagReader::next(RawMessage& m) {
  Record& r = rec_;  // kept from call to call: its field list is not allocated again for every message
  std::string why;
  while (!done_) {
    if (in_chunk()) {
      const size_t at = cpos_;
      bool cut = false;
      if (!read_record(cd_, cn_, cpos_, r, &why, "the chunk", &cut)) {
        if (cut && !cut_error_.empty()) return stop(cut_error_);  // the record the end of the file cut in two
        return stop(chunk_what_ + ": record at chunk offset " + std::to_string(at) + ": " + why);
      }
      uint32_t conn = 0;
      if (r.op == 0x07 || r.op == 0x02) {
        if (!field_u32(r, "conn", conn, &why)) return stop(chunk_what_ + ": record at chunk offset " + std::to_string(at) + ": " + why);
      }
      if (r.op == 0x07) {
        std::vector<Field> cf;
        if (!parse_fields(r.data, r.data_len, cf, &why))
          return stop(chunk_what_ + ": connection record at chunk offset " + std::to_string(at) + ": " + why);
        if (!conns_.count(conn)) conns_[conn] = {conn, text(find(r.fields, "topic")), text(find(cf, "type")),
                                                 text(find(cf, "message_definition")), Encoding::kRos1};
      } else if (r.op == 0x02) {
        const Field* t = find(r.fields, "time");
        if (!t || t->n != 8) return stop(chunk_what_ + ": message at chunk offset " + std::to_string(at) + " has no 8-byte 'time'");
        if (!conns_.count(conn))
          return stop(chunk_what_ + ": message at chunk offset " + std::to_string(at) + " on unknown connection " + std::to_string(conn));
        m.conn = conn;
        m.time_ns = int64_t(rd<uint32_t>(t->v)) * 1000000000 + rd<uint32_t>(t->v + 4);
        m.data = r.data;
        m.size = r.data_len;
        m.in_chunk = !top_level_;
        m.chunk_at = chunk_at_;
        m.offset = top_level_ ? chunk_at_ : at;
        if (!cut_error_.empty()) ++cut_messages_;
        return true;
      }
      continue;
    }
    if (pos_ >= size_) {
      if (!cut_error_.empty()) return stop(cut_error_);  // every whole record of the cut chunk read
      // Cut between two records: nothing is cut in two, but a bag without its header record, or whose header
      // puts the index past the end, lost what came after the cut.
      if (!header_seen_) return stop("no bag header record after the '#ROSBAG V2.0' line (file truncated?)");
      if (index_pos_ > size_)
        return stop("ends at byte " + std::to_string(size_) + ", before its index at byte " + std::to_string(index_pos_) +
                    " (the bag header's index_pos): file truncated? (the messages up to the cut are read)");
      done_ = true;
      return false;
    }
    const size_t at = pos_;
    f_->read_ahead(at);
    const uint8_t* rp = nullptr;  // the record's bytes
    bool cut = false;
    if (!read_file_record(*f_, at, pos_, r, &rp, &why, &cut)) {
      pos_ = at;
      if (!cut) return stop("record at byte " + std::to_string(at) + ": " + why);
      const std::string e = cut_record(at, why);  // "": an uncompressed chunk whose whole records are read first
      if (!e.empty()) return stop(e);
      continue;
    }
    if (r.op == 0x05) {
      const Field* c = find(r.fields, "compression");
      uint32_t usize = 0;
      if (!c || !field_u32(r, "size", usize, &why)) return stop("chunk at byte " + std::to_string(at) + ": no 'compression'/'size'");
      const std::string method = text(c);
      chunk_what_ = "chunk at byte " + std::to_string(at) + " (" + escaped(method) + ")";
      if (method == "none") {
        if (usize != r.data_len) return stop(chunk_what_ + ": size field " + std::to_string(usize) + " != data length " + std::to_string(r.data_len));
        cd_ = r.data;
        cn_ = r.data_len;
      } else {
        std::string e;
        ChunkAhead::Result res;
        if (ahead_.take(at, buf_, res)) e = std::move(res.error);
        else e = decompress(method, r.data, r.data_len, usize, buf_);
        if (!e.empty()) return stop(chunk_what_ + ": " + e);
        cd_ = buf_.data();
        cn_ = buf_.size();
        prefetch_after(pos_);
      }
      cpos_ = 0;
      chunk_at_ = at;
      top_level_ = false;
    } else if (r.op == 0x07 || r.op == 0x02) {
      // Outside chunks (allowed, rare): handle through the chunk path with a one-record "chunk".
      chunk_what_ = "top level";
      cd_ = rp;
      cn_ = pos_ - at;
      cpos_ = 0;
      chunk_at_ = at;
      top_level_ = true;
    } else if (r.op == 0x03) {
      header_seen_ = true;
      const Field* ip = find(r.fields, "index_pos");
      if (ip && ip->n == 8) std::memcpy(&index_pos_, ip->v, 8);  // 0: unindexed (a recording still open)
    }
    // 0x04 index data, 0x06 chunk info and unknown ops: skipped.
  }
  return false;
}

}  // namespace fploc::rec
