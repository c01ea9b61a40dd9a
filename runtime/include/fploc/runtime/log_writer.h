// Writing typed LCM messages into an LCM log file (lcm::LogFile, the format lcm-logger writes and
// `fploc replay` / lcm-logplayer read), for the tools that make logs without a bus: the simulator, the
// CARMEN importer, test fixtures.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace fploc::rt {

// One event stamped `utime` on `channel`; `buf` is scratch space reused between calls. Throws naming the
// channel when the write fails (disk full, closed file).
template <class Msg>
void write_event(lcm::LogFile& log, int64_t utime, const std::string& channel, const Msg& m, std::vector<uint8_t>& buf) {
  const int n = m.getEncodedSize();
  buf.resize(size_t(n));
  m.encode(buf.data(), 0, n);
  lcm::LogEvent ev;
  ev.eventnum = 0;
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = n;
  ev.data = buf.data();
  if (log.writeEvent(&ev) != 0) throw std::runtime_error("cannot write LCM log event on " + channel);
}

}  // namespace fploc::rt
