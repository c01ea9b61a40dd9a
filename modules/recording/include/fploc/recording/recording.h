// ROS recordings (ROS 1 bag format 2.0, ROS 2 MCAP, ROS 2 rosbag2 sqlite3 .db3) read as one stream of raw messages in file order.
// No transport, no ROS: a Connection says what a topic carries (type, encoding), a RawMessage points at
// its serialized bytes. Readers never throw on bad input: the first problem stops the stream with ONE
// error naming the file, the byte offset and the record; everything delivered before it stays valid.
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

namespace fploc::rec {

enum class Encoding { kRos1, kCdr, kOther };  // ROS 1 serialization, ROS 2 CDR (XCDR1), anything else (not decoded)

struct Connection {
  uint32_t id = 0;
  std::string topic;
  std::string type;        // normalised "pkg/Name" (MCAP's "pkg/msg/Name" loses its "/msg")
  std::string definition;  // message definition text when the file has it
  Encoding encoding = Encoding::kRos1;
};

struct RawMessage {
  uint32_t conn = 0;
  int64_t time_ns = 0;            // record time (bag: receipt time; MCAP: log_time)
  const uint8_t* data = nullptr;  // valid until the next call to next()
  size_t size = 0;
  // Where it is in the file (for messages about it): the byte offset of its record, or, for a record in a
  // chunk, the chunk's byte offset and the record's offset among the chunk's (uncompressed) records.
  bool in_chunk = false;
  uint64_t chunk_at = 0;
  uint64_t offset = 0;
  bool row = false;  // a rosbag2 .db3's message: offset is its id in the messages table
};

// "byte N", "chunk at byte N, record at chunk offset K" or (.db3) "message id N".
inline std::string where(const RawMessage& m) {
  if (m.row) return "message id " + std::to_string(m.offset);
  return m.in_chunk ? "chunk at byte " + std::to_string(m.chunk_at) + ", record at chunk offset " + std::to_string(m.offset)
                    : "byte " + std::to_string(m.offset);
}

struct TopicSummary {
  std::string type;
  uint64_t count = 0;
  int64_t first_ns = 0, last_ns = 0;
};

class Recording {
 public:
  virtual ~Recording() = default;
  // Next message in file order; false at the end or on the first error (see error()).
  virtual bool next(RawMessage& m) = 0;
  const std::map<uint32_t, Connection>& connections() const { return conns_; }
  const std::string& error() const { return error_; }
  // Bytes of the file consumed so far (progress), and its size.
  virtual uint64_t position() const = 0;
  uint64_t size() const { return size_; }
  const std::string& format() const { return format_; }  // "bag 2.0", "mcap" or "rosbag2 sqlite3"
  // True when [p, p + n) lies in the recording's mapped (or borrowed) bytes, which stay valid and
  // unchanged until the Recording is destroyed: not a decompressed copy, and not the bytes of a file's
  // sequential reads (FileBytes::seq(), reused), which is where a file's records are read from.
  virtual bool stable(const uint8_t* p, size_t n) const {
    (void)p, (void)n;
    return false;
  }

 protected:
  bool fail(const std::string& what) {
    if (error_.empty()) error_ = what;
    return false;
  }
  std::map<uint32_t, Connection> conns_;
  std::string error_;
  uint64_t size_ = 0;
  std::string format_;
};

class ReadWindow;

// A read-only view of the whole file (mmap), or of memory the caller owns (fuzzing, tests). The readers'
// sequential pass takes the file's bytes with seq() (pread into a reused buffer: read_window.h says why);
// the mapping stays for random access (the look-ahead for the next compressed chunk, whose bytes the
// decompressing thread reads from it).
class FileBytes {
 public:
  FileBytes();
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  ~FileBytes();
  // read_bytes: the size of the sequential reads (0: the default, 1 MiB; tests use small ones).
  bool map(const std::string& path, std::string* err, size_t read_bytes = 0);
  void borrow(const uint8_t* data, size_t size) { data_ = data, size_ = size; }
  const uint8_t* data() const { return data_; }
  size_t size() const { return size_; }
  // The bytes [off, off + n) (within the file) for the sequential pass: valid until the next seq() call;
  // nullptr when a read fails (read_error()). Borrowed memory and records of more than 64 MiB (a huge or
  // corrupt length: no buffer of that size) come from the mapping.
  const uint8_t* seq(size_t off, size_t n);
  // The same bytes without reading: from seq()'s buffer when they are in it, else from the mapping
  // (pointers seq() gave out stay valid).
  const uint8_t* view(size_t off, size_t n) const;
  const std::string& read_error() const;
  // Readers call this with their position: the kernel is asked (MADV_WILLNEED, asynchronous) to read
  // the next 64 MiB of a mapped file ahead, 32 MiB at a time, so a cold file streams from the disk
  // the way `cat` reads it instead of waiting for its small readahead window at every read.
  void read_ahead(size_t pos);

 private:
  size_t advised_ = 0;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  void* mapped_ = nullptr;
  std::unique_ptr<ReadWindow> window_;  // set when the file is mapped
};

// Opens a bag, an MCAP file or a rosbag2 .db3 (SQLite) file by its magic bytes, or a rosbag2 bag folder
// (metadata.yaml + NAME_N.db3 files, read one after the other; a folder of one .mcap opens that file). Returns nullptr with *err set when the file cannot be
// read or is neither; a reader is returned even when its stream ends early (its error() says why).
// read_bytes: FileBytes::map's (0: the default).
std::unique_ptr<Recording> open_recording(const std::string& path, std::string* err, size_t read_bytes = 0);
// Same over memory (the name is used in messages).
std::unique_ptr<Recording> open_recording_memory(const uint8_t* data, size_t size, const std::string& name,
                                                 std::string* err);

// Topics, types, counts and times: a full pass over the stream (errors as for next()).
std::map<std::string, TopicSummary> summarize(Recording& r);

}  // namespace fploc::rec
