#include "fploc/recording/recording.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "read_window.h"
#include "readers.h"

namespace fploc::rec {

FileBytes::FileBytes() = default;

FileBytes::~FileBytes() {
  if (mapped_) munmap(mapped_, size_);
}

bool FileBytes::map(const std::string& path, std::string* err, size_t read_bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return *err = path + ": " + std::strerror(errno), false;
  struct stat st {};
  if (fstat(fd, &st) != 0) {
    *err = path + ": " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {  // a directory, a FIFO: mmap said "No such device"
    *err = path + (S_ISDIR(st.st_mode) ? ": is a directory" : ": not a regular file");
    ::close(fd);
    return false;
  }
  size_ = size_t(st.st_size);
  if (size_ > 0) {
    void* p = mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      *err = path + ": mmap: " + std::strerror(errno);
      ::close(fd);
      return false;
    }
    madvise(p, size_, MADV_SEQUENTIAL);  // the look-ahead and the compressed chunks go forward through it
    mapped_ = p;
    data_ = static_cast<const uint8_t*>(p);
  }
  posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);  // a larger readahead window for the preads
  window_ = std::make_unique<ReadWindow>(read_bytes ? read_bytes : ReadWindow::kDefaultReadBytes);
  window_->open(fd, size_);  // the window closes fd
  return true;
}

const uint8_t* FileBytes::seq(size_t off, size_t n) {
  constexpr size_t kMaxWindowRecord = size_t(64) << 20;
  if (!window_ || (n > kMaxWindowRecord && data_)) return data_ + off;
  return window_->get(off, n);
}

const uint8_t* FileBytes::view(size_t off, size_t n) const {
  const uint8_t* p = window_ ? window_->peek(off, n) : nullptr;
  return p ? p : data_ + off;
}

const std::string& FileBytes::read_error() const {
  static const std::string none;
  return window_ ? window_->error() : none;
}

void FileBytes::read_ahead(size_t pos) {
  constexpr size_t kAhead = size_t(64) << 20, kStep = size_t(32) << 20;
  if (!mapped_ || advised_ >= size_ || pos + (kAhead - kStep) < advised_) return;
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  const size_t from = std::max(advised_, pos) & ~(page - 1);
  const size_t to = std::min(size_, pos + kAhead);
  if (to > from) madvise(static_cast<uint8_t*>(mapped_) + from, to - from, MADV_WILLNEED);
  advised_ = to;
}

namespace {
// path: the file (empty: the bytes are the caller's memory).
std::unique_ptr<Recording> by_magic(std::unique_ptr<FileBytes> f, const std::string& name, std::string* err,
                                    const std::string& path = "") {
  const uint8_t* d = f->data();
  const size_t n = f->size();
  if (n == 0) {
    *err = name + ": empty file (0 B)";
    return nullptr;
  }
  if (n < 8 && std::memcmp(d, "\x89MCAP0\r\n", n) == 0) {
    *err = name + ": " + std::to_string(n) + " B, cut inside the MCAP magic (file truncated?)";
    return nullptr;
  }
  if (n >= 8 && d[0] == 0x89 && std::memcmp(d + 1, "MCAP", 4) == 0) return std::make_unique<McapReader>(std::move(f), name);
  if (n >= 9 && std::memcmp(d, "#ROSBAG V", 9) == 0) {
    if (n < 13 && std::memcmp(d, "#ROSBAG V2.0\n", n) == 0) {
      *err = name + ": " + std::to_string(n) + " B, cut inside the '#ROSBAG V2.0' line (file truncated?)";
      return nullptr;
    }
    if (n < 13 || std::memcmp(d, "#ROSBAG V2.0\n", 13) != 0) {
      *err = name + ": ROS bag version " + std::string(reinterpret_cast<const char*>(d) + 9, std::min<size_t>(n - 9, 3)) +
             " is not supported (only 2.0; `rosbag fix` converts 1.2)";
      return nullptr;
    }
    return std::make_unique<BagReader>(std::move(f), name);
  }
  if (n >= 16 && std::memcmp(d, "SQLite format 3", 16) == 0)  // (the 16th byte is the NUL)
    return path.empty() ? open_db3_memory(d, n, name, err) : open_db3_files({path}, name, err);
  if (is_zstd_file(d, n)) {
    *err = zstd_file_error(name);
    return nullptr;
  }
  *err = name + ": neither a ROS 1 bag (#ROSBAG V2.0), an MCAP file nor a ROS 2 rosbag2 sqlite3 file (.db3)";
  return nullptr;
}
}  // namespace

std::unique_ptr<Recording> open_recording(const std::string& path, std::string* err, size_t read_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) return open_bag_folder(path, err, read_bytes);
  auto f = std::make_unique<FileBytes>();
  if (!f->map(path, err, read_bytes)) return nullptr;
  return by_magic(std::move(f), path, err, path);
}

std::unique_ptr<Recording> open_recording_memory(const uint8_t* data, size_t size, const std::string& name,
                                                 std::string* err) {
  auto f = std::make_unique<FileBytes>();
  f->borrow(data, size);
  return by_magic(std::move(f), name, err);
}

std::map<std::string, TopicSummary> summarize(Recording& r) {
  std::map<std::string, TopicSummary> out;
  std::map<uint32_t, TopicSummary*> by_conn;
  RawMessage m;
  while (r.next(m)) {
    auto& p = by_conn[m.conn];
    if (!p) {
      const auto& c = r.connections().at(m.conn);
      p = &out[c.topic];
      p->type = c.type;
    }
    if (p->count == 0 || m.time_ns < p->first_ns) p->first_ns = m.time_ns;
    if (p->count == 0 || m.time_ns > p->last_ns) p->last_ns = m.time_ns;
    ++p->count;
  }
  // Topics whose connection was seen but that carry no message.
  for (const auto& [id, c] : r.connections())
    if (!out.count(c.topic)) out[c.topic].type = c.type;
  return out;
}

}  // namespace fploc::rec
