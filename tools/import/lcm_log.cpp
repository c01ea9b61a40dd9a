#include "lcm_log.h"

#include <cstring>

namespace fploc::import {

bool LcmLog::open(const std::string& path) {
  log_ = lcm_eventlog_create(path.c_str(), "w");
  if (!log_) return false;
  stdio_buf_.resize(4 << 20);
  setvbuf(log_->f, stdio_buf_.data(), _IOFBF, stdio_buf_.size());
  return true;
}

bool LcmLog::write_parts(const std::string& channel, int64_t utime, const uint8_t* a, size_t na, const uint8_t* b,
                         size_t nb) {
  if (!log_) return false;
  const size_t n = na + nb;
  if (n > size_t(INT32_MAX)) return false;
  uint8_t h[28];
  const uint32_t sync = __builtin_bswap32(0xEDA1DA01u);
  const uint64_t num = __builtin_bswap64(uint64_t(log_->eventcount)), ts = __builtin_bswap64(uint64_t(utime));
  const uint32_t cl = __builtin_bswap32(uint32_t(channel.size())), dl = __builtin_bswap32(uint32_t(n));
  std::memcpy(h, &sync, 4);
  std::memcpy(h + 4, &num, 8);
  std::memcpy(h + 12, &ts, 8);
  std::memcpy(h + 20, &cl, 4);
  std::memcpy(h + 24, &dl, 4);
  FILE* f = log_->f;
  if (fwrite_unlocked(h, 1, sizeof h, f) != sizeof h || fwrite_unlocked(channel.data(), 1, channel.size(), f) != channel.size() ||
      (na && fwrite_unlocked(a, 1, na, f) != na) || (nb && fwrite_unlocked(b, 1, nb, f) != nb))
    return false;
  ++log_->eventcount;
  ++events_;
  bytes_ += n;
  return true;
}

void LcmLog::close() {
  if (log_) lcm_eventlog_destroy(log_);  // fclose: writes what is still buffered
  log_ = nullptr;
}

}  // namespace fploc::import
