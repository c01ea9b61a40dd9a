// The two readers behind open_recording() (internal).
#pragma once
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "chunk_ahead.h"
#include "fploc/recording/recording.h"

namespace fploc::rec {

// A little-endian value at p (both formats are little-endian; x86/ARM hosts too).
template <class T>
T rd(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// A name from the file (a compression method) for a message: bytes outside printable ASCII as \xHH.
inline std::string escaped(const std::string& s) {
  std::string out;
  for (const char ch : s) {
    const auto u = uint8_t(ch);
    if (u >= 0x20 && u < 0x7F && ch != '\\') {
      out += ch;
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    }
  }
  return out;
}

// What both readers share: the file (read in order with FileBytes::seq(); its mapping for the look-ahead),
// the position, the first error (which stops the stream, prefixed with the file name), and the chunk
// being read (in seq()'s buffer, or decompressed into buf_).
class FileReader : public Recording {
 public:
  uint64_t position() const override { return pos_; }
  bool stable(const uint8_t* p, size_t n) const override {
    const uint8_t* d = f_->data();
    return d && p >= d && n <= f_->size() && size_t(p - d) <= f_->size() - n;
  }

 protected:
  FileReader(std::unique_ptr<FileBytes> f, std::string name, std::string format) : f_(std::move(f)), name_(std::move(name)) {
    format_ = std::move(format);
    size_ = f_->size();
  }
  // True while records of the current chunk are left (false, and out of the chunk, at its end).
  bool in_chunk() {
    if (cd_ && cpos_ >= cn_) cd_ = nullptr;
    return cd_ != nullptr;
  }
  bool stop(const std::string& what) {
    done_ = true;
    return fail(name_ + ": " + what + (cut_error_.empty() ? "" : "; the chunk's " + std::to_string(cut_messages_) +
                                                                   " whole message" + (cut_messages_ == 1 ? " before the cut was read" : "s before the cut were read")));
  }
  // The file ends inside the uncompressed chunk being read: its whole records are read, then this error.
  std::string cut_error_;
  uint64_t cut_messages_ = 0;
  std::unique_ptr<FileBytes> f_;
  std::string name_;
  size_t pos_ = 0;
  bool done_ = false;
  // The chunk being read.
  const uint8_t* cd_ = nullptr;
  size_t cn_ = 0, cpos_ = 0, chunk_at_ = 0;
  bool top_level_ = false;  // the "chunk" is one record outside chunks, at byte chunk_at_
  std::string chunk_what_;
  std::vector<uint8_t> buf_;
};

namespace bag {
// One header field of a bag record ("name=value"), pointing into the record.
struct Field {
  std::string_view name;
  const uint8_t* v = nullptr;
  size_t n = 0;
};
// One bag record: op, header fields, data (pointers into the file or the chunk).
struct Record {
  uint8_t op = 0;
  std::vector<Field> fields;
  const uint8_t* data = nullptr;
  size_t data_len = 0;
};
}  // namespace bag

// ROS 1 bag format 2.0, read sequentially (the index at the end is not needed: an unindexed bag or one
// cut short by a crash reads up to its last whole record). Chunks: none, bz2, lz4.
// Compressed chunks: while one chunk's messages are read, the next chunk is decompressed on a second
// thread when it gets a CPU (chunk_ahead.h; libbz2 decodes ~20-40 MB/s: the import's whole cost);
// results and errors are the sequential ones, taken in file order.
class BagReader : public FileReader {
 public:
  BagReader(std::unique_ptr<FileBytes> f, std::string name);
  bool next(RawMessage& m) override;

 private:
  void prefetch_after(size_t pos);  // starts decompressing the compressed chunk that follows pos, if any
  std::string cut_record(size_t at, const std::string& why);
  std::string cut_cause(size_t at) const;  // why a record at `at` can run past the end: truncated, or a bad length
  ChunkAhead ahead_;
  bag::Record rec_;  // the record being read (its field list reused)
  bool header_seen_ = false;  // the bag header record (op 0x03) was read
  uint64_t index_pos_ = 0;    // its index_pos (0: none written yet)
};

// MCAP (data section in file order: chunks none/zstd/lz4, or messages outside chunks; the summary
// section and indexes are not needed).
// Compressed chunks are decompressed (and their CRC-32 computed) one ahead on a second thread, as in
// BagReader; results and errors are taken in file order.
class McapReader : public FileReader {
 public:
  McapReader(std::unique_ptr<FileBytes> f, std::string name);
  bool next(RawMessage& m) override;

 private:
  void prefetch_after(size_t pos);  // starts on the next compressed chunk after pos, if any
  // The data section's CRC-32, kept up to byte crc_at_ as the records go by (an uncompressed chunk's
  // records are read once for both CRCs: zlib's crc32_combine), so Data End needs no second pass.
  void crc_upto(size_t to);
  uint32_t data_crc_ = 0;
  size_t crc_at_ = 0;
  ChunkAhead ahead_;
  // One record's content (opcode and body); false with *why on a bad record.
  bool on_record(uint8_t op, const uint8_t* b, size_t n, RawMessage* m, bool* is_message, std::string* why);
  std::map<uint16_t, std::pair<std::string, std::string>> schemas_;  // id -> (name, encoding)
};

// rosbag2 sqlite3 (db3_reader.cpp): one .db3 in memory, .db3 files read in the given order, a bag folder.
// nullptr with *err when the first file cannot be read (not SQLite, no topics/messages table, damaged schema).
std::unique_ptr<Recording> open_db3_memory(const uint8_t* data, size_t size, const std::string& name, std::string* err);
std::unique_ptr<Recording> open_db3_files(const std::vector<std::string>& files, const std::string& name, std::string* err);
std::unique_ptr<Recording> open_bag_folder(const std::string& dir, std::string* err, size_t read_bytes);
bool is_zstd_file(const uint8_t* d, size_t n);
std::string zstd_file_error(const std::string& name);

}  // namespace fploc::rec
