#include "lcm_log.h"

#include <cstring>

namespace fploc::import {

namespace {
constexpr int kBuffers = 3;  // one being filled, up to two queued for (or in) the writer
}

bool LcmLog::open(const std::string& path) {
  log_ = lcm_eventlog_create(path.c_str(), "w");
  if (!log_) return false;
  setvbuf(log_->f, nullptr, _IONBF, 0);  // the buffers below are the buffering
  cur_.resize(kBufBytes);
  fill_ = 0;
  for (int i = 1; i < kBuffers; ++i) free_.emplace_back(kBufBytes);
  done_ = failed_ = false;
  thread_ = std::thread([this] { writer(); });
  return true;
}

void LcmLog::writer() {
  std::unique_lock<std::mutex> lk(mu_);
  for (;;) {
    cv_.wait(lk, [this] { return done_ || !full_.empty(); });
    if (full_.empty()) return;  // done and drained
    auto [b, n] = std::move(full_.front());
    full_.pop_front();
    lk.unlock();
    const bool ok = fwrite(b.data(), 1, n, log_->f) == n;
    lk.lock();
    if (!ok) failed_ = true;
    free_.push_back(std::move(b));
    cv_.notify_all();
  }
}

void LcmLog::hand_over() {
  if (!fill_) return;
  std::unique_lock<std::mutex> lk(mu_);
  full_.emplace_back(std::move(cur_), fill_);
  cv_.notify_all();
  cv_.wait(lk, [this] { return !free_.empty(); });
  cur_ = std::move(free_.back());
  free_.pop_back();
  fill_ = 0;
}

bool LcmLog::write_parts(const std::string& channel, int64_t utime, const uint8_t* a, size_t na, const uint8_t* b,
                         size_t nb) {
  if (!log_ || failed_) return false;
  const size_t n = na + nb;
  if (n > size_t(INT32_MAX)) return false;
  const size_t need = 28 + channel.size() + n;
  if (fill_ + need > cur_.size()) {
    hand_over();
    if (need > cur_.size()) cur_.resize(need);  // a message larger than a buffer gets a larger buffer
  }
  uint8_t* p = cur_.data() + fill_;
  const uint32_t sync = __builtin_bswap32(0xEDA1DA01u);
  const uint64_t num = __builtin_bswap64(uint64_t(log_->eventcount)), ts = __builtin_bswap64(uint64_t(utime));
  const uint32_t cl = __builtin_bswap32(uint32_t(channel.size())), dl = __builtin_bswap32(uint32_t(n));
  std::memcpy(p, &sync, 4);
  std::memcpy(p + 4, &num, 8);
  std::memcpy(p + 12, &ts, 8);
  std::memcpy(p + 20, &cl, 4);
  std::memcpy(p + 24, &dl, 4);
  p += 28;
  std::memcpy(p, channel.data(), channel.size());
  p += channel.size();
  if (na) std::memcpy(p, a, na);
  if (nb) std::memcpy(p + na, b, nb);
  fill_ += need;
  ++log_->eventcount;
  ++events_;
  bytes_ += n;
  return true;
}

bool LcmLog::close() {
  if (!log_) return !failed_;
  {
    std::unique_lock<std::mutex> lk(mu_);
    if (fill_) full_.emplace_back(std::move(cur_), fill_);
    fill_ = 0;
    done_ = true;
    cv_.notify_all();
  }
  thread_.join();
  lcm_eventlog_destroy(log_);
  log_ = nullptr;
  full_.clear();
  free_.clear();
  cur_.clear();
  return !failed_;
}

}  // namespace fploc::import
