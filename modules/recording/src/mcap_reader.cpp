// MCAP: magic "\x89MCAP0\r\n", records (u8 opcode, u64 length, body), footer, magic. Strings and byte
// arrays carry a u32 length, maps a u32 byte length, chunk records a u64 length. Opcodes used: 0x01
// Header, 0x02 Footer, 0x03 Schema, 0x04 Channel, 0x05 Message, 0x06 Chunk, 0x0F Data End; everything
// else (indexes, statistics, attachments, metadata, summary offsets) is skipped.
// CRCs (CRC-32 as zlib's crc32, computed with ISA-L; 0 = "not computed" and not checked): a Chunk's uncompressed_crc over its
// uncompressed records, and Data End's data_section_crc over every byte before the Data End record
// (leading magic included). A mismatch is one error naming the chunk's / record's byte offset.
#include <isa-l/crc.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "readers.h"
#include "fploc/recording/decompress.h"

namespace fploc::rec {
namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// Bounded little-endian reads over one record body.
struct Body {
  const uint8_t* p;
  size_t n, i = 0;
  bool ok = true;
  template <class T>
  T get() {
    if (!ok || n - i < sizeof(T)) return ok = false, T{};
    const T v = rd<T>(p + i);
    i += sizeof(T);
    return v;
  }
  std::string str() {
    const uint32_t len = get<uint32_t>();
    if (!ok || len > n - i) return ok = false, std::string();
    std::string s(reinterpret_cast<const char*>(p + i), len);
    i += len;
    return s;
  }
  void skip_u32_prefixed() {
    const uint32_t len = get<uint32_t>();
    if (!ok || len > n - i) ok = false;
    else i += len;
  }
};

// "sensor_msgs/msg/PointCloud2" -> "sensor_msgs/PointCloud2" (ROS 1 and ROS 2 names compare equal).
std::string normalise_type(std::string t) {
  const auto k = t.find("/msg/");
  if (k != std::string::npos) t.erase(k, 4);
  return t;
}

// The fuzz targets (FPLOC_FUZZ_SKIP_CRC) compare no CRC, so mutations reach the records and decoders
// behind it instead of stopping at the checksum.
#ifdef FPLOC_FUZZ_SKIP_CRC
constexpr bool kCheckCrc = false;
#else
constexpr bool kCheckCrc = true;
#endif

// CRC-32 as zlib's crc32 computes it (the gzip polynomial, reflected), by ISA-L's carry-less-multiply
// version: 5x zlib's speed here, which made the CRCs a quarter of a zstd MCAP import's CPU time.
uint32_t crc32_of(const uint8_t* p, size_t n) { return crc32_gzip_refl(0, p, n); }

std::string hex32(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08x", v);
  return b;
}

// A Chunk record's header fields (body = the record's body); false when cut short.
struct ChunkHeader {
  uint64_t usize = 0;
  uint32_t crc = 0;
  std::string method;
  const uint8_t* records = nullptr;
  uint64_t rlen = 0;
};
bool parse_chunk(const uint8_t* body, uint64_t len, ChunkHeader& h) {
  Body b{body, len};
  b.get<uint64_t>();
  b.get<uint64_t>();
  h.usize = b.get<uint64_t>();
  h.crc = b.get<uint32_t>();
  h.method = b.str();
  h.rlen = b.get<uint64_t>();
  if (!b.ok || h.rlen > len - b.i) return false;
  h.records = body + b.i;
  return true;
}

}  // namespace

void McapReader::crc_upto(size_t to) {
  if (!kCheckCrc || to <= crc_at_) return;
  data_crc_ = crc32_gzip_refl(data_crc_, f_->view(crc_at_, to - crc_at_), to - crc_at_);
  crc_at_ = to;
}

void McapReader::prefetch_after(size_t pos) {
  if (ahead_.pending()) return;
  const uint8_t* d = f_->data();
  for (int k = 0; k < 256 && size_ - pos >= 9; ++k) {  // message indexes and the like between chunks skipped
    const uint8_t op = d[pos];
    const uint64_t len = rd<uint64_t>(d + pos + 1);
    if (len > size_ - pos - 9 || op == 0x02 || op == 0x0F) return;
    if (op == 0x06) {
      ChunkHeader h;
      if (!parse_chunk(d + pos + 9, len, h) || h.method.empty()) return;  // reported when reached
      ahead_.start({pos, h.method, h.records, size_t(h.rlen), size_t(h.usize), kCheckCrc && h.crc != 0});
      return;
    }
    pos += 9 + len;
  }
}

McapReader::McapReader(std::unique_ptr<FileBytes> f, std::string name) : FileReader(std::move(f), std::move(name), "mcap") {
  if (size_ < 8 || std::memcmp(f_->data(), kMagic, 8) != 0) {
    stop("not an MCAP file (no magic)");
    return;
  }
  pos_ = 8;
}

bool McapReader::on_record(uint8_t op, const uint8_t* p, size_t n, RawMessage* m, bool* is_message, std::string* why) {
  *is_message = false;
  Body b{p, n};
  if (op == 0x03) {  // Schema
    const uint16_t id = b.get<uint16_t>();
    std::string name = b.str(), enc = b.str();
    b.skip_u32_prefixed();
    if (!b.ok) return *why = "schema record cut short", false;
    schemas_[id] = {std::move(name), std::move(enc)};
  } else if (op == 0x04) {  // Channel
    const uint16_t id = b.get<uint16_t>();
    const uint16_t schema = b.get<uint16_t>();
    std::string topic = b.str(), msg_enc = b.str();
    b.skip_u32_prefixed();  // metadata map
    if (!b.ok) return *why = "channel record cut short", false;
    if (conns_.count(id)) return true;  // repeated in chunks and the summary
    Connection c;
    c.id = id;
    c.topic = std::move(topic);
    auto s = schemas_.find(schema);
    if (schema != 0 && s == schemas_.end()) return *why = "channel " + std::to_string(id) + " refers to unknown schema " + std::to_string(schema), false;
    if (s != schemas_.end()) c.type = normalise_type(s->second.first);
    c.encoding = msg_enc == "cdr" ? Encoding::kCdr : msg_enc == "ros1" ? Encoding::kRos1 : Encoding::kOther;
    if (c.encoding == Encoding::kOther) c.type += " [" + msg_enc + "]";
    conns_[id] = std::move(c);
  } else if (op == 0x05) {  // Message
    const uint16_t ch = b.get<uint16_t>();
    b.get<uint32_t>();  // sequence
    const uint64_t log_time = b.get<uint64_t>();
    b.get<uint64_t>();  // publish time
    if (!b.ok) return *why = "message record shorter than its fixed fields", false;
    if (!conns_.count(ch)) return *why = "message on unknown channel " + std::to_string(ch), false;
    m->conn = ch;
    m->time_ns = int64_t(log_time);
    m->data = p + b.i;
    m->size = n - b.i;
    *is_message = true;
  }
  return true;
}

bool McapReader::next(RawMessage& m) {
  std::string why;
  bool is_msg = false;
  while (!done_) {
    if (in_chunk()) {
      const size_t at = cpos_;
      if (cn_ - cpos_ < 9) {
        if (!cut_error_.empty()) return stop(cut_error_);  // the record the end of the file cut in two
        return stop(chunk_what_ + ": record header cut at chunk offset " + std::to_string(at));
      }
      const uint8_t op = cd_[cpos_];
      const uint64_t len = rd<uint64_t>(cd_ + cpos_ + 1);
      if (len > cn_ - cpos_ - 9) {
        if (!cut_error_.empty()) return stop(cut_error_);
        return stop(chunk_what_ + ": record (op 0x" + std::to_string(op) + ") at chunk offset " + std::to_string(at) + " runs past the chunk");
      }
      cpos_ += 9 + len;
      if (!on_record(op, cd_ + at + 9, len, &m, &is_msg, &why)) return stop(chunk_what_ + ": record at chunk offset " + std::to_string(at) + ": " + why);
      if (is_msg) {
        m.in_chunk = true;
        m.chunk_at = chunk_at_;
        m.offset = at;
        if (!cut_error_.empty()) ++cut_messages_;
        return true;
      }
      continue;
    }
    if (!cut_error_.empty()) return stop(cut_error_);  // every whole record of the cut chunk read
    const size_t at = pos_;
    f_->read_ahead(at);
    if (size_ - pos_ < 9) return stop("record at byte " + std::to_string(at) + ": cut off (file truncated? no footer)");
    const uint8_t* d = f_->seq(at, 9);  // the record's header, then (its length checked) the whole record
    if (!d) return stop("record at byte " + std::to_string(at) + ": " + f_->read_error());
    const uint8_t op = d[0];
    const uint64_t len = rd<uint64_t>(d + 1);
    if (len > size_ - pos_ - 9) {
      const std::string past = ": length " + std::to_string(len) + " runs past the end of the file (file size " + std::to_string(size_) +
                               " B; file truncated, or the length damaged)";
      if (op != 0x06) return stop("record (opcode " + std::to_string(op) + ") at byte " + std::to_string(at) + past);
      // A chunk cut by the end of the file: an uncompressed one's whole records are read first (its CRC cannot be
      // checked); a compressed one cannot be decompressed.
      const size_t avail = size_ - pos_ - 9;
      const uint8_t* cp = f_->seq(at, 9 + avail);
      if (!cp) return stop("record at byte " + std::to_string(at) + ": " + f_->read_error());
      Body b{cp + 9, avail};
      b.get<uint64_t>();
      b.get<uint64_t>();
      b.get<uint64_t>();
      b.get<uint32_t>();
      const std::string method = b.str();
      b.get<uint64_t>();
      const std::string chunk = "chunk at byte " + std::to_string(at) + " (" + (method.empty() ? "none" : escaped(method)) + ")";
      if (!b.ok) return stop(chunk + past + ": its header is cut");
      if (!method.empty()) return stop(chunk + past + ": a cut compressed chunk cannot be decompressed, its messages are lost");
      cut_error_ = chunk + past;
      chunk_what_ = chunk;
      cd_ = cp + 9 + b.i;
      cn_ = avail - b.i;
      cpos_ = 0;
      chunk_at_ = at;
      pos_ = size_;
      continue;
    }
    if (!(d = f_->seq(at, 9 + size_t(len)))) return stop("record at byte " + std::to_string(at) + ": " + f_->read_error());
    pos_ += 9 + len;
    const uint8_t* body = d + 9;
    if (op != 0x06 && op != 0x0F) crc_upto(pos_);
    if (op == 0x02) {  // Footer: then the closing magic
      const uint8_t* magic = size_ - pos_ < 8 ? nullptr : f_->seq(pos_, 8);
      if (!magic && size_ - pos_ >= 8) return stop("footer at byte " + std::to_string(at) + ": " + f_->read_error());
      if (!magic || std::memcmp(magic, kMagic, 8) != 0) return stop("footer at byte " + std::to_string(at) + " is not followed by the MCAP magic");
      pos_ = size_;
      done_ = true;
      return false;
    }
    if (op == 0x0F) {  // Data End
      Body b{body, len};
      const uint32_t crc = b.get<uint32_t>();
      if (!b.ok) return stop("data end record at byte " + std::to_string(at) + ": cut short");
      if (kCheckCrc && crc != 0) {
        crc_upto(at);
        const uint32_t got = data_crc_;
        if (got != crc)
          return stop("data section (bytes 0.." + std::to_string(at) + "): CRC-32 " + hex32(got) + " != " + hex32(crc) +
                      " recorded in the data end record at byte " + std::to_string(at) + " (file damaged)");
      }
      continue;
    }
    if (op == 0x06) {
      ChunkHeader h;
      if (!parse_chunk(body, len, h)) return stop("chunk at byte " + std::to_string(at) + ": header cut short");
      chunk_what_ = "chunk at byte " + std::to_string(at) + " (" + (h.method.empty() ? "none" : escaped(h.method)) + ")";
      bool crc_known = false;
      uint32_t got = 0;
      if (h.method.empty()) {
        if (h.usize != h.rlen) return stop(chunk_what_ + ": uncompressed size " + std::to_string(h.usize) + " != records length " + std::to_string(h.rlen));
        cd_ = h.records;
        cn_ = h.rlen;
        if (kCheckCrc) {  // the records' CRC once, for the chunk and (combined) for the data section
          crc_upto(at + 9 + size_t(h.records - body));
          got = crc32_of(cd_, cn_), crc_known = true;
          data_crc_ = uint32_t(crc32_combine(data_crc_, got, z_off_t(cn_)));
          crc_at_ += cn_;
        }
      } else {
        std::string e;
        ChunkAhead::Result res;
        if (ahead_.take(at, buf_, res)) {
          e = std::move(res.error);
          got = res.crc, crc_known = res.has_crc;
        } else {
          e = decompress(h.method, h.records, h.rlen, h.usize, buf_);
        }
        if (!e.empty()) return stop(chunk_what_ + ": " + e);
        cd_ = buf_.data();
        cn_ = buf_.size();
        prefetch_after(pos_);
      }
      if (kCheckCrc && h.crc != 0) {
        if (!crc_known) got = crc32_of(cd_, cn_);
        if (got != h.crc) {
          cd_ = nullptr;
          return stop(chunk_what_ + ": CRC-32 of the " + std::to_string(cn_) + " uncompressed bytes is " + hex32(got) +
                      ", the chunk says " + hex32(h.crc) + " (chunk damaged)");
        }
      }
      crc_upto(pos_);
      cpos_ = 0;
      chunk_at_ = at;
      continue;
    }
    if (!on_record(op, body, len, &m, &is_msg, &why)) return stop("record at byte " + std::to_string(at) + ": " + why);
    if (is_msg) {
      m.in_chunk = false;
      m.offset = at;
      return true;
    }
  }
  return false;
}

}  // namespace fploc::rec
