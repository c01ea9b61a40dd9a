// An LCM event log (the format lcm-logger writes and lcm-logplayer and fploc replay read), opened and
// closed with lcm's eventlog API. Events are framed here (sync word 0xEDA1DA01, event number,
// timestamp, channel length, data length, channel, data; big-endian) into 256 KiB buffers that a
// writer thread hands to the file while the importer goes on decoding: its write() time (the copy into
// the page cache) overlaps the reading and decoding, and a buffer still sits in the cache when it is
// copied (4 MiB buffers cost more CPU: they are read back from memory). A message can
// be written from two parts (its header and a payload that stays where it is) without assembling it
// first; a payload that stays valid until close() (`stable`: the recording's mapped bytes) is not
// copied at all: the writer thread hands it to writev() beside the framing, so the only copy of the
// recording's bytes is the kernel's into the log's page cache. (The readers now read a file with pread
// into a reused buffer, not stable: only records over 64 MiB and recordings in memory still come from
// a mapping; docs/notes/import.md, "Sequential reads with pread".) close() (also on a bad input, where
// the importer stops) writes everything before it.
//
// Direct I/O (open(path, true)): the log is written with O_DIRECT from 4 KiB-aligned 16 MiB buffers, at
// 4 KiB-aligned file offsets, so it never enters the page cache: no page-cache folios to allocate, fill
// and write back later (on this VM: 0.21-0.26 s of system time per GB, about all of `cat`'s CPU for
// the same GB, docs/notes/import.md). Payloads are copied into the buffer (no writev from the mapped
// recording: O_DIRECT wants aligned memory); the bytes past the last aligned offset of a full buffer
// move to the start of the next one; the last < 4 KiB of the log are written without O_DIRECT at
// close(). Where the file system refuses O_DIRECT (open or a write: EINVAL), the same bytes go
// through the page cache instead: the file is the same either way. Less CPU (no page cache to fill),
// but the import then waits for the disk: an option (`fploc import --direct-io`), not the default.
#pragma once
#include <lcm/eventlog.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <vector>

namespace fploc::import {

class LcmLog {
 public:
  // direct: write with O_DIRECT where the file system takes it (see above).
  bool open(const std::string& path, bool direct = false);
  bool direct() const { return direct_.load(); }  // false after a fall-back to the page cache
  template <class Msg>
  bool write(const std::string& channel, int64_t utime, const Msg& m) {
    buf_.resize(size_t(m.getEncodedSize()));
    if (m.encode(buf_.data(), 0, int(buf_.size())) < 0) return false;
    return write_raw(channel, utime, buf_.data(), buf_.size());
  }
  bool write_raw(const std::string& channel, int64_t utime, const uint8_t* data, size_t n) {
    return write_parts(channel, utime, data, n, nullptr, 0);
  }
  // One event whose data is a followed by b. b_stable: b stays valid (unchanged) until close(), so it
  // is written from where it is. False once a write to the file has failed.
  bool write_parts(const std::string& channel, int64_t utime, const uint8_t* a, size_t na, const uint8_t* b, size_t nb,
                   bool b_stable = false);
  // One event of n data bytes that the caller encodes in place, at the returned pointer, before the next
  // call (no scratch buffer, no copy); nullptr once a write to the file has failed.
  uint8_t* begin_event(const std::string& channel, int64_t utime, size_t n);
  // Writes what is buffered and closes the file; false when a write failed.
  bool close();
  ~LcmLog() { close(); }
  uint64_t events() const { return events_; }
  uint64_t bytes() const { return bytes_; }

 private:
  static constexpr size_t kBufBytes = 256 << 10;
  static constexpr size_t kDirectBufBytes = size_t(16) << 20;  // direct I/O: bytes per buffer and write
  static constexpr size_t kAlign = 4096;                      // direct I/O: memory and file offset alignment
  static constexpr size_t kMaxSegs = 512;               // iovecs per writev (IOV_MAX is 1024)
  static constexpr size_t kBatchBytes = size_t(1) << 20;  // bytes per batch, stable payloads included
  // Each writev ends at a multiple of 128 KiB in the file (what cat writes at a time), so the kernel
  // puts the log in page-cache folios of at most 128 KiB. A write of 1 MiB or more lets it take 1-2 MiB
  // folios, and on a VM whose free memory is handed back to the host (virtio-balloon free page
  // reporting hands back the large free blocks) touching those costs 0.3-2.4 s of system time per GB
  // instead of 0.25 s (bench: docs/notes/import.md, "Speed, fifth round").
  static constexpr size_t kWriteStep = size_t(128) << 10;
  template <class T>
  struct AlignedAlloc {  // buffers at kAlign (what O_DIRECT wants of memory)
    using value_type = T;
    AlignedAlloc() = default;
    template <class U>
    AlignedAlloc(const AlignedAlloc<U>&) {}
    T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(kAlign))); }
    void deallocate(T* p, size_t) { ::operator delete(p, std::align_val_t(kAlign)); }
    template <class U>
    bool operator==(const AlignedAlloc<U>&) const { return true; }
  };
  // What one writev writes: framing and copied data in `bytes`, stable payloads where they are.
  struct Batch {
    struct Seg {
      const uint8_t* p;  // a stable payload, or nullptr: bytes[off, off + len)
      size_t off, len;
    };
    std::vector<uint8_t, AlignedAlloc<uint8_t>> bytes;
    size_t fill = 0, total = 0;
    std::vector<Seg> segs;
    size_t direct_len = 0;  // direct I/O: bytes[0, direct_len) to write (an aligned length, unless last)
    bool last = false;      // direct I/O: the log's end (its unaligned tail written without O_DIRECT)
    void clear() { fill = total = direct_len = 0, segs.clear(), last = false; }
  };
  void hand_over();  // the current batch to the writer thread; takes a free one
  // Frames one event of n data bytes of which `copy` are copied into the batch (n - copy follow as a
  // stable segment); returns where the copied data go.
  uint8_t* frame(const std::string& channel, int64_t utime, size_t n, size_t copy);
  void writer();
  bool write_batch(const Batch& b);
  bool write_direct(const Batch& b);  // direct I/O: b.bytes[0, b.direct_len)
  bool write_all(const uint8_t* p, size_t n);
  lcm_eventlog_t* log_ = nullptr;
  std::vector<uint8_t> buf_;  // encoding scratch for write()
  Batch cur_;                 // being filled
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Batch> full_;  // for the writer
  std::vector<Batch> free_;
  bool done_ = false;
  std::atomic<bool> failed_{false};
  std::thread thread_;
  uint64_t events_ = 0, bytes_ = 0;
  size_t file_pos_ = 0;  // bytes written to the file (writer thread)
  bool direct_mode_ = false;  // batches are built for direct I/O (contiguous, aligned lengths)
  std::atomic<bool> direct_{false};  // the batches are written with O_DIRECT (set at open; the writer may fall back)
  size_t buf_bytes_ = kBufBytes, batch_bytes_ = kBatchBytes;
};

}  // namespace fploc::import
