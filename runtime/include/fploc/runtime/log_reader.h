// Reading an LCM log file to the end, and saying whether what was read is the whole file. lcm::LogFile skips what is
// not an event (a ROS bag given as the log, a damaged stretch) and stops at a cut event without a word; and an event
// whose length field is damaged makes it allocate and read that length (2 GB for 0x7fffffff: liblcm's buffer size
// overflows and it reads into a null pointer). LogReader looks at each event's header before liblcm reads it: an event
// that runs past the end of the file ends the reading, with the event's byte offset in problem(). For the tools that
// read logs to the end (`fploc replay`, `fploc map diff`, `fploc eval`).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <cstdio>
#include <string>

namespace fploc::rt {

class LogReader {
 public:
  explicit LogReader(const std::string& path);
  bool good() { return log_.good(); }
  // The next event, or nullptr at the end of the file or at the first event that cannot be read whole.
  const lcm::LogEvent* next();
  int64_t events() const { return events_; }
  // Empty when the events read are the whole file (or its size cannot be read); else why not, starting with the path:
  // "P: no LCM event in its N B (not an LCM event log; ...)", "P: event K at byte O: its data length L runs past the
  // end of the file (N B: truncated, or the length damaged); the K - 1 events before it were read", or "P: K events are B of its N B; the rest is not
  // an LCM event (truncated or damaged?)".
  std::string problem() const;

 private:
  // At the next event's header (after the bytes liblcm skips looking for its sync word): whether the event fits in
  // the file; else damaged_ says why. The file position is left where it was.
  bool next_fits();
  std::string path_;
  lcm::LogFile log_;
  uint64_t size_ = 0;
  bool have_size_ = false;
  int64_t events_ = 0;
  uint64_t bytes_ = 0;
  std::string damaged_;
};

}  // namespace fploc::rt
