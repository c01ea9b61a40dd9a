// An LCM event log (the format lcm-logger writes and lcm-logplayer and fploc replay read), opened and
// closed with lcm's eventlog API; events are framed here (sync word 0xEDA1DA01, event number,
// timestamp, channel length, data length, channel, data; big-endian) into a 4 MiB stdio buffer, so a
// 1 GB import makes ~250 large write() calls instead of several per event, and a message can be
// written from two parts (its header and a payload that stays where it is) without assembling it
// first. On a bad input the importer stops and closes the log: everything written up to there is in
// the file.
#pragma once
#include <lcm/eventlog.h>

#include <cstdint>
#include <string>
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
  // One event whose data is a followed by b.
  bool write_parts(const std::string& channel, int64_t utime, const uint8_t* a, size_t na, const uint8_t* b, size_t nb);
  void close();
  ~LcmLog() { close(); }
  uint64_t events() const { return events_; }
  uint64_t bytes() const { return bytes_; }

 private:
  lcm_eventlog_t* log_ = nullptr;
  std::vector<uint8_t> buf_;
  std::vector<char> stdio_buf_;
  uint64_t events_ = 0, bytes_ = 0;
};

}  // namespace fploc::import
