#include "lcm_log.h"

namespace fploc::import {

bool LcmLog::open(const std::string& path) {
  log_ = lcm_eventlog_create(path.c_str(), "w");
  return log_ != nullptr;
}

bool LcmLog::write_raw(const std::string& channel, int64_t utime, const uint8_t* data, size_t n) {
  lcm_eventlog_event_t e{};
  e.eventnum = int64_t(events_);
  e.timestamp = utime;
  e.channellen = int32_t(channel.size());
  e.datalen = int32_t(n);
  e.channel = const_cast<char*>(channel.c_str());
  e.data = const_cast<uint8_t*>(data);
  if (lcm_eventlog_write_event(log_, &e) != 0) return false;
  ++events_;
  bytes_ += n;
  return true;
}

void LcmLog::close() {
  if (log_) lcm_eventlog_destroy(log_);
  log_ = nullptr;
}

}  // namespace fploc::import
