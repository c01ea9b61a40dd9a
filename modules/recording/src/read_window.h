// The readers' sequential pass over a file: pread(2) into one reused buffer (internal; FileBytes).
// Why not the mapping, which the readers keep for their look-ahead: on a VM with nested paging, the
// first touch of each 4 KiB page of a 1 GB mapping costs more than copying the page. On the AMD
// EPYC VM of docs/notes/import.md, writing 1 GB to a new file from the mapping took 0.67-1.12 s of
// system time against 0.19-0.21 s from pread into a reused 128 KiB buffer (the buffer's pages stay
// mapped; the kernel reads the page cache through its own linear mapping).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace fploc::rec {

class ReadWindow {
 public:
  static constexpr size_t kDefaultReadBytes = size_t(1) << 20;
  explicit ReadWindow(size_t read_bytes = kDefaultReadBytes) : read_bytes_(read_bytes ? read_bytes : 1) {}
  ReadWindow(const ReadWindow&) = delete;
  ReadWindow& operator=(const ReadWindow&) = delete;
  ~ReadWindow();
  // Reads from fd (closed by the destructor), a file of `size` bytes.
  void open(int fd, size_t size);
  // The file's bytes [off, off + n) in the buffer: read (pread, at least read_bytes at a time, up to
  // the end of the file) unless they are there already. The pointer stays valid until the next get()
  // that reads. nullptr when [off, off + n) is not within the file or a read fails (error() says
  // why; a file that shrank since open() is a failed read).
  const uint8_t* get(size_t off, size_t n);
  // The bytes when they are in the buffer now, else nullptr; never reads (pointers given out stay valid).
  const uint8_t* peek(size_t off, size_t n) const;
  const std::string& error() const { return error_; }

 private:
  bool fill(size_t off, size_t n);    // the buffer from off, with at least n bytes
  void reserve(size_t n, size_t keep_from);  // capacity >= n, the bytes from buf_[keep_from] moved to the start
  bool read_at(size_t off, uint8_t* to, size_t n);
  size_t read_bytes_;
  int fd_ = -1;
  size_t size_ = 0;
  std::unique_ptr<uint8_t[]> buf_;
  size_t cap_ = 0;
  size_t at_ = 0, len_ = 0;  // the buffer holds the file's bytes [at_, at_ + len_)
  std::string error_;
};

}  // namespace fploc::rec
