// An LCM event log (the format lcm-logger writes and lcm-logplayer and fploc replay read), opened and
// closed with lcm's eventlog API. Events are framed here (sync word 0xEDA1DA01, event number,
// timestamp, channel length, data length, channel, data; big-endian) into 256 KiB buffers that a
// writer thread hands to the file while the importer goes on decoding: its write() time (the copy into
// the page cache) overlaps the reading and decoding, and a buffer still sits in the cache when it is
// copied (4 MiB buffers cost more CPU: they are read back from memory). A message can
// be written from two parts (its header and a payload that stays where it is) without assembling it
// first. close() (also on a bad input, where the importer stops) writes everything before it.
#pragma once
#include <lcm/eventlog.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace fploc::import {

class LcmLog {
 public:
  bool open(const std::string& path);
  template <class Msg>
  bool write(const std::string& channel, int64_t utime, const Msg& m) {
    buf_.resize(size_t(m.getEncodedSize()));
    if (m.encode(buf_.data(), 0, int(buf_.size())) < 0) return false;
    return write_raw(channel, utime, buf_.data(), buf_.size());
  }
  bool write_raw(const std::string& channel, int64_t utime, const uint8_t* data, size_t n) {
    return write_parts(channel, utime, data, n, nullptr, 0);
  }
  // One event whose data is a followed by b. False once a write to the file has failed.
  bool write_parts(const std::string& channel, int64_t utime, const uint8_t* a, size_t na, const uint8_t* b, size_t nb);
  // Writes what is buffered and closes the file; false when a write failed.
  bool close();
  ~LcmLog() { close(); }
  uint64_t events() const { return events_; }
  uint64_t bytes() const { return bytes_; }

 private:
  static constexpr size_t kBufBytes = 256 << 10;
  void hand_over();  // the current buffer to the writer thread; takes a free one
  void writer();
  lcm_eventlog_t* log_ = nullptr;
  std::vector<uint8_t> buf_;  // encoding scratch for write()
  std::vector<uint8_t> cur_;  // being filled
  size_t fill_ = 0;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::pair<std::vector<uint8_t>, size_t>> full_;  // (buffer, bytes) for the writer
  std::vector<std::vector<uint8_t>> free_;
  bool done_ = false;
  std::atomic<bool> failed_{false};
  std::thread thread_;
  uint64_t events_ = 0, bytes_ = 0;
};

}  // namespace fploc::import
