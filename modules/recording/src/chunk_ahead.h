// One compressed chunk decompressed ahead on a worker thread while the reader reads the one before it
// (internal; BagReader and McapReader). The reader never waits for a worker that has not started: a
// job still queued when the reader reaches its chunk is taken back and decompressed by the reader
// itself. On a loaded machine the worker may not get a CPU for milliseconds, and waiting for it at
// every chunk made a zstd MCAP import several times slower than decompressing in the reader; on an
// idle core the worker runs as soon as it is given the job and the two overlap.
#pragma once
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace fploc::rec {

class ChunkAhead {
 public:
  struct Job {
    size_t at = 0;  // the chunk record's offset in the file (its identity)
    std::string method;
    const uint8_t* in = nullptr;  // compressed bytes (stay valid while the reader lives)
    size_t n = 0, expected = 0;
    bool crc = false;  // also the CRC-32 of the result
  };
  struct Result {
    std::string error;  // decompress()'s
    bool has_crc = false;
    uint32_t crc = 0;
  };
  ChunkAhead() = default;
  ChunkAhead(const ChunkAhead&) = delete;
  ChunkAhead& operator=(const ChunkAhead&) = delete;
  ~ChunkAhead();
  bool pending();        // a job given and not taken yet
  void start(Job job);   // only when !pending()
  // The chunk at `at`: its bytes into out (out's old buffer goes to the worker for the next job) and
  // true; false when no job is pending for that chunk (a job for another chunk is dropped).
  bool take(size_t at, std::vector<uint8_t>& out, Result& r);
  // What the worker does, also used by the reader when it takes a queued job back.
  static void run_job(const Job& j, std::vector<uint8_t>& out, Result& r);

 private:
  void worker();
  enum class State { kIdle, kQueued, kRunning, kDone };
  std::mutex mu_;
  std::condition_variable cv_;
  State state_ = State::kIdle;
  bool stop_ = false;
  Job job_;
  Result res_;
  std::vector<uint8_t> buf_;  // the worker's output (owned by the worker while running)
  std::thread thread_;
};

}  // namespace fploc::rec
