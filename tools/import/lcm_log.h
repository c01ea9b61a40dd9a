// An LCM event log written with lcm's eventlog API (what lcm-logger writes and lcm-logplayer and
// fploc replay read). Each event is flushed to the file as it is written, so a log cut short by an
// error up to there is complete.
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
  bool write_raw(const std::string& channel, int64_t utime, const uint8_t* data, size_t n);
  void close();
  ~LcmLog() { close(); }
  uint64_t events() const { return events_; }
  uint64_t bytes() const { return bytes_; }

 private:
  lcm_eventlog_t* log_ = nullptr;
  std::vector<uint8_t> buf_;
  uint64_t events_ = 0, bytes_ = 0;
};

}  // namespace fploc::import
