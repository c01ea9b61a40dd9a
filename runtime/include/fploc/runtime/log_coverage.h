// Whether the events read from an LCM log file are the whole file: lcm::LogFile skips what is not an event (a ROS
// bag given as the log, a damaged stretch) and stops at a cut event without a word; the file's size says whether
// it did. For the tools that read logs to the end (`fploc replay`, `fploc map diff`).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>

namespace fploc::rt {

class LogCoverage {
 public:
  // Every event read, in order.
  void add(const lcm::LogEvent& ev) {
    ++events_;
    bytes_ += 28 + ev.channel.size() + uint64_t(ev.datalen);  // sync, number, time, two lengths, channel, data
  }
  int64_t events() const { return events_; }
  // Empty when the events are the whole file (or its size cannot be read); else why not, starting with the path:
  // "P: no LCM event in its N B (not an LCM event log; ...)" or "P: K events are B of its N B; the rest is not an
  // LCM event (truncated or damaged?)".
  std::string problem(const std::string& path) const {
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (ec || bytes_ == size) return {};
    if (events_ == 0)
      return path + ": no LCM event in its " + std::to_string(size) +
             " B (not an LCM event log; a ROS bag or MCAP goes through `fploc import` first)";
    return path + ": " + std::to_string(events_) + " events are " + std::to_string(bytes_) + " of its " +
           std::to_string(size) + " B; the rest is not an LCM event (truncated or damaged?)";
  }

 private:
  int64_t events_ = 0;
  uint64_t bytes_ = 0;
};

}  // namespace fploc::rt
