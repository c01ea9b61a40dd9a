#include "read_window.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace fploc::rec {

ReadWindow::~ReadWindow() {
  if (fd_ >= 0) ::close(fd_);
}

void ReadWindow::open(int fd, size_t size) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd, size_ = size, at_ = len_ = 0;
  error_.clear();
}

const uint8_t* ReadWindow::peek(size_t off, size_t n) const {
  if (off < at_ || off > at_ + len_ || n > at_ + len_ - off) return nullptr;
  return buf_.get() + (off - at_);
}

const uint8_t* ReadWindow::get(size_t off, size_t n) {
  if (const uint8_t* p = peek(off, n)) return p;
  if (off > size_ || n > size_ - off) {
    error_ = "bytes " + std::to_string(off) + "+" + std::to_string(n) + " asked past the end of the file";
    return nullptr;
  }
  return fill(off, n) ? buf_.get() : nullptr;
}

void ReadWindow::reserve(size_t n, size_t keep_from) {
  const size_t kept = len_ - keep_from;
  if (n <= cap_) {
    if (kept && keep_from) std::memmove(buf_.get(), buf_.get() + keep_from, kept);
    return;
  }
  // A record larger than the buffer: a buffer of its size (kept for the next ones).
  std::unique_ptr<uint8_t[]> b(new uint8_t[n]);
  if (kept) std::memcpy(b.get(), buf_.get() + keep_from, kept);
  buf_ = std::move(b);
  cap_ = n;
}

bool ReadWindow::fill(size_t off, size_t n) {
  // The part of [off, off + n) already buffered (a record cut by the last read) moves to the start of
  // the buffer; the rest is read after it, at least read_bytes_ in all: one pread per read_bytes_ of a
  // file of small records.
  const size_t want = std::min(size_ - off, std::max(n, read_bytes_));
  const size_t kept = (off >= at_ && off < at_ + len_) ? at_ + len_ - off : 0;
  reserve(want, kept ? off - at_ : len_);
  at_ = off, len_ = kept;
  if (!read_at(off + kept, buf_.get() + kept, want - kept)) {
    len_ = 0;
    return false;
  }
  len_ = want;
  return true;
}

bool ReadWindow::read_at(size_t off, uint8_t* to, size_t n) {
  while (n > 0) {
    const ssize_t r = ::pread(fd_, to, n, off_t(off));
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      error_ = "read at byte " + std::to_string(off) + ": " + std::strerror(errno);
      return false;
    }
    if (r == 0) {
      error_ = "read at byte " + std::to_string(off) + ": the file ends there, it was " + std::to_string(size_) +
               " B when opened (cut while being read?)";
      return false;
    }
    to += r, off += size_t(r), n -= size_t(r);
  }
  return true;
}

}  // namespace fploc::rec
