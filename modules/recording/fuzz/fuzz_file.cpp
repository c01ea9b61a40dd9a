// libFuzzer, differential: a recording read from a file (FileBytes: pread into a reused buffer, the mapping for
// the look-ahead) must give exactly what the same bytes give from memory: the same connections, messages (time,
// topic, bytes) and error text. The first input byte picks the file path's read size (small sizes put records
// across the buffer's end); the rest is the recording (a bag when it lacks the MCAP magic: the bag magic is
// prepended, as fuzz_bag does).
#include <sys/mman.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "fploc/recording/recording.h"

namespace {

using namespace fploc::rec;

struct Read {
  std::vector<std::string> messages;  // "topic time bytes"
  std::string error;
  bool opened = false;
};

Read read_all(std::unique_ptr<Recording> r, const std::string& open_err) {
  Read out;
  out.error = open_err;
  if (!r) return out;
  out.opened = true;
  RawMessage m;
  while (out.messages.size() < 20000 && r->next(m)) {
    const auto& c = r->connections().at(m.conn);
    out.messages.push_back(c.topic + " " + c.type + " " + std::to_string(m.time_ns) + " " +
                           std::string(reinterpret_cast<const char*>(m.data), m.size));
  }
  out.error = r->error();
  return out;
}

[[noreturn]] void mismatch(const char* what, const std::string& a, const std::string& b) {
  std::fprintf(stderr, "file and memory differ (%s):\n  file:   %.300s\n  memory: %.300s\n", what, a.c_str(), b.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const size_t read_bytes = 1 + size_t(data[0]) * 37;  // 1 .. 9436 bytes per read
  static const char kBag[] = "#ROSBAG V2.0\n";
  static const uint8_t kMcap[] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  std::vector<uint8_t> bytes;
  if (size - 1 < 8 || std::memcmp(data + 1, kMcap, 8) != 0) bytes.assign(kBag, kBag + 13);
  bytes.insert(bytes.end(), data + 1, data + size);

  const int fd = memfd_create("fuzz_file", 0);
  if (fd < 0) std::abort();
  if (write(fd, bytes.data(), bytes.size()) != ssize_t(bytes.size())) std::abort();
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  std::string file_err, mem_err;
  const Read f = read_all(open_recording(path, &file_err, read_bytes), file_err);
  const Read m = read_all(open_recording_memory(bytes.data(), bytes.size(), path, &mem_err), mem_err);
  close(fd);
  if (f.opened != m.opened) mismatch("opened", f.opened ? "yes" : "no", m.opened ? "yes" : "no");
  if (f.messages.size() != m.messages.size())
    mismatch("message count", std::to_string(f.messages.size()), std::to_string(m.messages.size()));
  for (size_t i = 0; i < f.messages.size(); ++i)
    if (f.messages[i] != m.messages[i]) mismatch("a message", f.messages[i], m.messages[i]);
  if (f.error != m.error) mismatch("error", f.error, m.error);
  return 0;
}
