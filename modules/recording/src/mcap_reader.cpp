// MCAP: magic "\x89MCAP0\r\n", records (u8 opcode, u64 length, body), footer, magic. Strings and byte
// arrays carry a u32 length, maps a u32 byte length, chunk records a u64 length. Opcodes used: 0x01
// Header, 0x02 Footer, 0x03 Schema, 0x04 Channel, 0x05 Message, 0x06 Chunk, 0x0F Data End; everything
// else (indexes, statistics, attachments, metadata, summary offsets) is skipped.
// CRCs (CRC-32, zlib's crc32; 0 = "not computed" and not checked): a Chunk's uncompressed_crc over its
// uncompressed records, and Data End's data_section_crc over every byte before the Data End record
// (leading magic included). A mismatch is one error naming the chunk's / record's byte offset.
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

// zlib's crc32 takes a uInt length: feed large spans in pieces.
uint32_t crc32_of(const uint8_t* p, size_t n) {
  uLong c = crc32(0L, Z_NULL, 0);
  while (n > 0) {
    const size_t k = std::min<size_t>(n, size_t(1) << 30);
    c = crc32(c, p, uInt(k));
    p += k;
    n -= k;
  }
  return uint32_t(c);
}

std::string hex32(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08x", v);
  return b;
}

}  // namespace

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
      if (cn_ - cpos_ < 9) return stop(chunk_what_ + ": record header cut at chunk offset " + std::to_string(at));
      const uint8_t op = cd_[cpos_];
      const uint64_t len = rd<uint64_t>(cd_ + cpos_ + 1);
      if (len > cn_ - cpos_ - 9) return stop(chunk_what_ + ": record (op 0x" + std::to_string(op) + ") at chunk offset " + std::to_string(at) + " runs past the chunk");
      cpos_ += 9 + len;
      if (!on_record(op, cd_ + at + 9, len, &m, &is_msg, &why)) return stop(chunk_what_ + ": record at chunk offset " + std::to_string(at) + ": " + why);
      if (is_msg) return true;
      continue;
    }
    const size_t at = pos_;
    f_->read_ahead(at);
    if (size_ - pos_ < 9) return stop("record at byte " + std::to_string(at) + ": cut off (file truncated? no footer)");
    const uint8_t* d = f_->data();
    const uint8_t op = d[pos_];
    const uint64_t len = rd<uint64_t>(d + pos_ + 1);
    if (len > size_ - pos_ - 9) return stop("record (opcode " + std::to_string(op) + ") at byte " + std::to_string(at) + ": length " + std::to_string(len) + " runs past the end (file truncated?)");
    pos_ += 9 + len;
    const uint8_t* body = d + at + 9;
    if (op == 0x02) {  // Footer: then the closing magic
      if (size_ - pos_ < 8 || std::memcmp(d + pos_, kMagic, 8) != 0) return stop("footer at byte " + std::to_string(at) + " is not followed by the MCAP magic");
      pos_ = size_;
      done_ = true;
      return false;
    }
    if (op == 0x0F) {  // Data End
      Body b{body, len};
      const uint32_t crc = b.get<uint32_t>();
      if (!b.ok) return stop("data end record at byte " + std::to_string(at) + ": cut short");
      if (kCheckCrc && crc != 0) {
        const uint32_t got = crc32_of(d, at);
        if (got != crc)
          return stop("data section (bytes 0.." + std::to_string(at) + "): CRC-32 " + hex32(got) + " != " + hex32(crc) +
                      " recorded in the data end record at byte " + std::to_string(at) + " (file damaged)");
      }
      continue;
    }
    if (op == 0x06) {
      Body b{body, len};
      b.get<uint64_t>();
      b.get<uint64_t>();
      const uint64_t usize = b.get<uint64_t>();
      const uint32_t crc = b.get<uint32_t>();  // of the uncompressed records (0 = not computed)
      const std::string method = b.str();
      const uint64_t rlen = b.get<uint64_t>();
      if (!b.ok || rlen > len - b.i) return stop("chunk at byte " + std::to_string(at) + ": header cut short");
      chunk_what_ = "chunk at byte " + std::to_string(at) + " (" + (method.empty() ? "none" : method) + ")";
      if (method.empty()) {
        if (usize != rlen) return stop(chunk_what_ + ": uncompressed size " + std::to_string(usize) + " != records length " + std::to_string(rlen));
        cd_ = body + b.i;
        cn_ = rlen;
      } else {
        const std::string e = decompress(method, body + b.i, rlen, usize, buf_);
        if (!e.empty()) return stop(chunk_what_ + ": " + e);
        cd_ = buf_.data();
        cn_ = buf_.size();
      }
      if (kCheckCrc && crc != 0) {
        const uint32_t got = crc32_of(cd_, cn_);
        if (got != crc) {
          cd_ = nullptr;
          return stop(chunk_what_ + ": CRC-32 of the " + std::to_string(cn_) + " uncompressed bytes is " + hex32(got) +
                      ", the chunk says " + hex32(crc) + " (chunk damaged)");
        }
      }
      cpos_ = 0;
      chunk_at_ = at;
      continue;
    }
    if (!on_record(op, body, len, &m, &is_msg, &why)) return stop("record at byte " + std::to_string(at) + ": " + why);
    if (is_msg) return true;
  }
  return false;
}

}  // namespace fploc::rec
