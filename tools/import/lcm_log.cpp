#include "lcm_log.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace fploc::import {

namespace {
constexpr int kBuffers = 3;  // one being filled, up to two queued for (or in) the writer
}

bool LcmLog::open(const std::string& path, bool direct) {
  log_ = lcm_eventlog_create(path.c_str(), "w");
  if (!log_) return false;
  setvbuf(log_->f, nullptr, _IONBF, 0);  // the batches below are the buffering (written with writev on its fd)
  // O_DIRECT on a regular file only (not /dev/null, a pipe, /dev/full); a file system that refuses it
  // (EINVAL) keeps the page cache.
  const int fd = fileno(log_->f);
  struct stat st {};
  bool dio = false;
  if (direct && fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
    const int fl = fcntl(fd, F_GETFL);
    dio = fl >= 0 && fcntl(fd, F_SETFL, fl | O_DIRECT) == 0;
  }
  direct_ = direct_mode_ = dio;
  buf_bytes_ = dio ? kDirectBufBytes : kBufBytes;
  batch_bytes_ = dio ? kDirectBufBytes : kBatchBytes;
  cur_ = Batch{};
  cur_.bytes.resize(buf_bytes_);
  for (int i = 1; i < kBuffers; ++i) {
    free_.emplace_back();
    free_.back().bytes.resize(buf_bytes_);
  }
  done_ = failed_ = false;
  file_pos_ = 0;
  thread_ = std::thread([this] { writer(); });
  return true;
}

bool LcmLog::write_batch(const Batch& b) {
  iovec iov[kMaxSegs];
  size_t n = 0;
  for (const auto& s : b.segs) iov[n++] = {const_cast<uint8_t*>(s.p ? s.p : b.bytes.data() + s.off), s.len};
  const int fd = fileno(log_->f);
  size_t i = 0;
  while (i < n) {
    // Up to the next multiple of kWriteStep in the file.
    const size_t room = kWriteStep - file_pos_ % kWriteStep;
    size_t k = i, tot = 0, cut_len = 0;
    while (k < n && iov[k].iov_len <= room - tot) tot += iov[k++].iov_len;
    if (k < n && tot < room) {  // this iovec crosses the boundary: its first part now
      cut_len = iov[k].iov_len;
      iov[k++].iov_len = room - tot;
    }
    const ssize_t w = ::writev(fd, iov + i, int(k - i));
    if (cut_len) iov[k - 1].iov_len = cut_len;
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    if (w == 0) return false;
    file_pos_ += size_t(w);
    size_t left = size_t(w);
    while (i < n && left >= iov[i].iov_len) left -= iov[i++].iov_len;
    if (i < n) {  // a partial write: the rest of this iovec next
      iov[i].iov_base = static_cast<uint8_t*>(iov[i].iov_base) + left;
      iov[i].iov_len -= left;
    }
  }
  return true;
}

bool LcmLog::write_all(const uint8_t* p, size_t n) {
  const int fd = fileno(log_->f);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0 && errno == EINVAL && direct_) {  // O_DIRECT refused (alignment, file system): the page cache from here on
      const int fl = fcntl(fd, F_GETFL);
      if (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_DIRECT) != 0) return false;
      direct_ = false;
      continue;
    }
    if (w <= 0) return false;
    p += w, n -= size_t(w), file_pos_ += size_t(w);
  }
  return true;
}

bool LcmLog::write_direct(const Batch& b) {
  const size_t n = b.direct_len, head = (b.last && direct_) ? n & ~(kAlign - 1) : n;
  if (!write_all(b.bytes.data(), head)) return false;
  if (head == n) return true;
  // The log's last partial block: without O_DIRECT (the file ends where the log ends).
  const int fd = fileno(log_->f);
  const int fl = fcntl(fd, F_GETFL);
  if (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_DIRECT) != 0) return false;
  direct_ = false;
  return write_all(b.bytes.data() + head, n - head);
}

void LcmLog::writer() {
  std::unique_lock<std::mutex> lk(mu_);
  for (;;) {
    cv_.wait(lk, [this] { return done_ || !full_.empty(); });
    if (full_.empty()) return;  // done and drained
    Batch b = std::move(full_.front());
    full_.pop_front();
    lk.unlock();
    const bool ok = failed_ || (direct_mode_ ? write_direct(b) : write_batch(b));
    lk.lock();
    if (!ok) failed_ = true;
    b.clear();
    free_.push_back(std::move(b));
    cv_.notify_all();
  }
}

void LcmLog::hand_over() {
  if (!direct_mode_) {
    if (cur_.segs.empty()) return;
    std::unique_lock<std::mutex> lk(mu_);
    full_.push_back(std::move(cur_));
    cv_.notify_all();
    cv_.wait(lk, [this] { return !free_.empty(); });
    cur_ = std::move(free_.back());
    free_.pop_back();
    cur_.clear();
    return;
  }
  // Direct I/O: the buffer up to its last aligned offset goes; the rest starts the next buffer.
  const size_t aligned = cur_.fill & ~(kAlign - 1);
  if (aligned == 0) return;
  std::unique_lock<std::mutex> lk(mu_);
  cv_.wait(lk, [this] { return !free_.empty(); });
  Batch next = std::move(free_.back());
  free_.pop_back();
  lk.unlock();
  next.clear();
  if (next.bytes.size() < buf_bytes_) next.bytes.resize(buf_bytes_);
  const size_t tail = cur_.fill - aligned;
  std::memcpy(next.bytes.data(), cur_.bytes.data() + aligned, tail);
  next.fill = next.total = tail;
  cur_.direct_len = aligned;
  lk.lock();
  full_.push_back(std::move(cur_));
  cur_ = std::move(next);
  cv_.notify_all();
}

uint8_t* LcmLog::frame(const std::string& channel, int64_t utime, size_t n, size_t copy_data) {
  const size_t copy = 28 + channel.size() + copy_data;
  if (direct_mode_) {  // every byte copied, one contiguous buffer
    if (cur_.fill + copy > cur_.bytes.size()) {
      hand_over();
      if (cur_.fill + copy > cur_.bytes.size()) cur_.bytes.resize((cur_.fill + copy + kAlign - 1) & ~(kAlign - 1));
    }
  } else if (cur_.fill + copy > cur_.bytes.size() || cur_.segs.size() + 2 > kMaxSegs || cur_.total >= batch_bytes_) {
    hand_over();
    if (copy > cur_.bytes.size()) cur_.bytes.resize(copy);  // a message larger than a buffer gets a larger buffer
  }
  uint8_t* p = cur_.bytes.data() + cur_.fill;
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
  // The copied bytes extend the last segment when it is the one just before them.
  auto& segs = cur_.segs;
  if (!direct_mode_) {
    if (!segs.empty() && !segs.back().p && segs.back().off + segs.back().len == cur_.fill) segs.back().len += copy;
    else segs.push_back({nullptr, cur_.fill, copy});
  }
  cur_.fill += copy;
  cur_.total += 28 + channel.size() + n;
  ++log_->eventcount;
  ++events_;
  bytes_ += n;
  return p;
}

uint8_t* LcmLog::begin_event(const std::string& channel, int64_t utime, size_t n) {
  if (!log_ || failed_ || n > size_t(INT32_MAX)) return nullptr;
  return frame(channel, utime, n, n);
}

bool LcmLog::write_parts(const std::string& channel, int64_t utime, const uint8_t* a, size_t na, const uint8_t* b,
                         size_t nb, bool b_stable) {
  if (!log_ || failed_) return false;
  const size_t n = na + nb;
  if (n > size_t(INT32_MAX)) return false;
  const bool by_ref = b_stable && nb > 0 && !direct_mode_;
  uint8_t* p = frame(channel, utime, n, na + (by_ref ? 0 : nb));
  if (na) std::memcpy(p, a, na);
  if (nb && !by_ref) std::memcpy(p + na, b, nb);
  if (by_ref) cur_.segs.push_back({b, 0, nb});
  return true;
}

bool LcmLog::close() {
  if (!log_) return !failed_;
  {
    std::unique_lock<std::mutex> lk(mu_);
    if (direct_mode_ && cur_.fill > 0) {
      cur_.direct_len = cur_.fill;
      cur_.last = true;
      full_.push_back(std::move(cur_));
    } else if (!cur_.segs.empty()) {
      full_.push_back(std::move(cur_));
    }
    cur_ = Batch{};
    done_ = true;
    cv_.notify_all();
  }
  thread_.join();
  lcm_eventlog_destroy(log_);
  log_ = nullptr;
  full_.clear();
  free_.clear();
  return !failed_;
}

}  // namespace fploc::import
