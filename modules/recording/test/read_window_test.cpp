// The readers' sequential reads (pread into a reused buffer, read_window.h): the bytes are the file's
// whatever the read size and wherever the buffer boundaries fall; a range past the end and a file cut
// while it is read are errors, not garbage.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <fstream>

#include "../src/read_window.h"
#include "test_util.h"

namespace fploc::rec::test {
namespace {

std::string write_file(const std::string& name, const std::vector<uint8_t>& bytes) {
  const std::string p = ::testing::TempDir() + "/" + name;
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  return p;
}

std::vector<uint8_t> pattern(size_t n) {
  std::vector<uint8_t> b(n);
  for (size_t i = 0; i < n; ++i) b[i] = uint8_t((i * 2654435761u) >> 11);
  return b;
}

TEST(ReadWindow, SameBytesAsTheFileAcrossBufferBoundaries) {
  const auto bytes = pattern(100003);
  const std::string p = write_file("window.bin", bytes);
  for (size_t read_bytes : {size_t(1), size_t(7), size_t(4096), size_t(1) << 20}) {
    ReadWindow w(read_bytes);
    w.open(::open(p.c_str(), O_RDONLY), bytes.size());
    // Records of 0..4999 bytes one after the other, each taken as the readers do: a prefix (its length),
    // then the whole record; now and then a step back (MCAP's data section CRC after Data End).
    size_t off = 0, k = 0;
    while (off < bytes.size()) {
      const size_t n = std::min(bytes.size() - off, (k * 7919) % 5000);
      const uint8_t* head = w.get(off, std::min<size_t>(n, 4));
      ASSERT_TRUE(head) << w.error();
      ASSERT_EQ(std::memcmp(head, &bytes[off], std::min<size_t>(n, 4)), 0) << read_bytes << " at " << off;
      const uint8_t* rec = w.get(off, n);
      ASSERT_TRUE(rec) << w.error();
      ASSERT_EQ(std::memcmp(rec, &bytes[off], n), 0) << read_bytes << " at " << off << " +" << n;
      EXPECT_EQ(w.peek(off, n), rec);  // in the buffer now: the same pointer, nothing read
      if (k % 17 == 3 && off > 3000) {
        const uint8_t* back = w.get(off - 3000, 100);
        ASSERT_TRUE(back);
        ASSERT_EQ(std::memcmp(back, &bytes[off - 3000], 100), 0);
      }
      off += n ? n : 1;
      ++k;
    }
    EXPECT_EQ(w.error(), "");
  }
}

TEST(ReadWindow, PeekNeverReads) {
  const auto bytes = pattern(10000);
  const std::string p = write_file("peek.bin", bytes);
  ReadWindow w(1000);
  w.open(::open(p.c_str(), O_RDONLY), bytes.size());
  EXPECT_EQ(w.peek(0, 1), nullptr);
  const uint8_t* a = w.get(500, 10);
  ASSERT_TRUE(a);
  EXPECT_EQ(w.peek(500, 1000), a);  // the read took read_bytes from 500
  EXPECT_EQ(w.peek(499, 1), nullptr);
  EXPECT_EQ(w.peek(1500, 1), nullptr);
  EXPECT_EQ(w.peek(500, 1001), nullptr);
}

TEST(ReadWindow, PastTheEndAndFileCutWhileReadAreErrors) {
  const auto bytes = pattern(50000);
  const std::string p = write_file("cut.bin", bytes);
  ReadWindow w(4096);
  w.open(::open(p.c_str(), O_RDONLY), bytes.size());
  EXPECT_EQ(w.get(bytes.size() - 3, 4), nullptr);
  EXPECT_NE(w.error().find("past the end"), std::string::npos) << w.error();
  ASSERT_TRUE(w.get(0, 100));
  ASSERT_EQ(::truncate(p.c_str(), 20000), 0);  // cut while being read (a recorder's file rotated away, a full disk)
  const uint8_t* last = w.get(16000, 8000);
  EXPECT_EQ(last, nullptr);
  EXPECT_NE(w.error().find("read at byte 20000: the file ends there, it was 50000 B when opened"), std::string::npos) << w.error();
}

}  // namespace
}  // namespace fploc::rec::test
