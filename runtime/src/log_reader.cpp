#include "fploc/runtime/log_reader.h"

#include <cstdint>
#include <filesystem>
#include <system_error>

namespace fploc::rt {

namespace {
constexpr uint32_t kSync = 0xEDA1DA01u;        // the LCM log format's sync word (big-endian on disk)
constexpr uint64_t kHeader = 4 + 8 + 8 + 4 + 4;  // sync, event number, time stamp, channel length, data length

uint32_t be32(const unsigned char* b) { return uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | b[3]; }
}  // namespace

LogReader::LogReader(const std::string& path) : path_(path), log_(path, "r") {
  std::error_code ec;
  size_ = std::filesystem::file_size(path, ec);
  have_size_ = !ec;
}

bool LogReader::next_fits() {
  FILE* f = log_.getFilePtr();
  if (!f || !have_size_) return true;
  const off_t start = ftello(f);
  if (start < 0) return true;
  // As liblcm does: skip to the sync word.
  uint32_t word = 0;
  int c = 0;
  off_t at = start;
  while ((c = std::fgetc(f)) != EOF) {
    word = word << 8 | uint32_t(c);
    ++at;
    if (word == kSync) break;
  }
  bool fits = true;
  unsigned char h[kHeader - 4];
  if (word == kSync && std::fread(h, 1, sizeof h, f) == sizeof h) {
    const int32_t channel_len = int32_t(be32(h + 16)), data_len = int32_t(be32(h + 20));
    const uint64_t header_at = uint64_t(at) - 4, body_at = header_at + kHeader;
    const uint64_t left = size_ > body_at ? size_ - body_at : 0;
    const std::string where = path_ + ": event " + std::to_string(events_ + 1) + " at byte " + std::to_string(header_at) + ": ";
    const std::string before = "; the " + std::to_string(events_) + " events before it were read";
    if (channel_len <= 0 || channel_len >= 1000) {
      damaged_ = where + "its channel length " + std::to_string(channel_len) + " is not one (1 .. 999)" + before;
      fits = false;
    } else if (data_len < 0 || uint64_t(channel_len) + uint64_t(data_len) > left) {
      damaged_ = where + "its data length " + std::to_string(data_len) + " runs past the end of the file (" +
                 std::to_string(size_) + " B: truncated, or the length damaged)" + before;
      fits = false;
    } else if (data_len == INT32_MAX) {  // liblcm's buffer of data length + 1 overflows, whatever the file's size
      damaged_ = where + "its data length " + std::to_string(data_len) + " is damaged (liblcm cannot read it)" + before;
      fits = false;
    }
  }
  // A header cut short, or no sync word left: liblcm reads nothing more; problem() says so from the byte counts.
  std::clearerr(f);
  fseeko(f, start, SEEK_SET);
  return fits;
}

const lcm::LogEvent* LogReader::next() {
  if (!damaged_.empty() || !next_fits()) return nullptr;
  const lcm::LogEvent* ev = log_.readNextEvent();
  if (ev) {
    ++events_;
    bytes_ += kHeader + ev->channel.size() + uint64_t(ev->datalen);
  }
  return ev;
}

std::string LogReader::problem() const {
  if (!damaged_.empty()) return damaged_;
  if (!have_size_ || bytes_ == size_) return {};
  if (events_ == 0)
    return path_ + ": no LCM event in its " + std::to_string(size_) +
           " B (not an LCM event log; a ROS bag or MCAP goes through `fploc import` first)";
  return path_ + ": " + std::to_string(events_) + " events are " + std::to_string(bytes_) + " of its " +
         std::to_string(size_) + " B; the rest is not an LCM event (truncated or damaged?)";
}

}  // namespace fploc::rt
