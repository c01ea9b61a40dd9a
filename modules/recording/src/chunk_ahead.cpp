#include "chunk_ahead.h"

#include <isa-l/crc.h>

#include <utility>

#include "fploc/recording/decompress.h"

namespace fploc::rec {

ChunkAhead::~ChunkAhead() {
  {
    std::lock_guard<std::mutex> lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ChunkAhead::run_job(const Job& j, std::vector<uint8_t>& out, Result& r) {
  r.error = decompress(j.method, j.in, j.n, j.expected, out);
  r.has_crc = r.error.empty() && j.crc;
  r.crc = r.has_crc ? crc32_gzip_refl(0, out.data(), out.size()) : 0;
}

bool ChunkAhead::pending() {
  std::lock_guard<std::mutex> lk(mu_);
  return state_ != State::kIdle;
}

void ChunkAhead::start(Job job) {
  {
    std::lock_guard<std::mutex> lk(mu_);
    job_ = std::move(job);
    state_ = State::kQueued;
    if (!thread_.joinable()) thread_ = std::thread([this] { worker(); });
  }
  cv_.notify_all();
}

bool ChunkAhead::take(size_t at, std::vector<uint8_t>& out, Result& r) {
  std::unique_lock<std::mutex> lk(mu_);
  if (state_ == State::kIdle) return false;
  if (state_ == State::kQueued) {  // not started: taken back (dropped when it is another chunk)
    state_ = State::kIdle;
    if (job_.at != at) return false;
    const Job j = job_;
    lk.unlock();
    run_job(j, out, r);
    return true;
  }
  cv_.wait(lk, [this] { return state_ == State::kDone; });
  state_ = State::kIdle;
  if (job_.at != at) return false;
  std::swap(out, buf_);
  r = std::move(res_);
  return true;
}

void ChunkAhead::worker() {
  std::unique_lock<std::mutex> lk(mu_);
  for (;;) {
    cv_.wait(lk, [this] { return stop_ || state_ == State::kQueued; });
    if (stop_) return;
    state_ = State::kRunning;
    const Job j = job_;
    lk.unlock();
    Result r;
    run_job(j, buf_, r);
    lk.lock();
    res_ = std::move(r);
    state_ = State::kDone;
    cv_.notify_all();
  }
}

}  // namespace fploc::rec
