// The readers' sequential reads (pread into a reused buffer, read_window.h): the bytes are the file's
// whatever the read size and wherever the buffer boundaries fall; a range past the end and a file cut
// while it is read are errors, not garbage. And the readers over a file (through the buffer) give what
// they give over the same bytes in memory: every message, and on a truncated or damaged file the same
// one error (byte offset, record) after the same messages.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <fstream>

#include "../src/read_window.h"
#include "fploc/recording/bag_writer.h"
#include "fploc/recording/mcap_writer.h"
#include "fploc/recording/recording.h"
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

// Every message and the error, read from the file with sequential reads of read_bytes.
std::vector<Msg> read_file(const std::string& path, size_t read_bytes, std::string* error) {
  std::string err;
  auto r = open_recording(path, &err, read_bytes);
  std::vector<Msg> out;
  if (!r) return *error = err, out;
  RawMessage m;
  while (r->next(m)) out.push_back({r->connections().at(m.conn).topic, m.time_ns, std::vector<uint8_t>(m.data, m.data + m.size)});
  *error = r->error();
  return out;
}

// The file (through the buffer, several read sizes) reads as the same bytes in memory (the mapping's
// path): the same messages, the same error.
void expect_file_as_memory(const std::vector<uint8_t>& bytes, const std::string& name, const std::string& what) {
  const std::string p = write_file(name, bytes);
  std::string mem_err;
  const auto mem = read_all(bytes.data(), bytes.size(), &mem_err, p);
  // 13 and 1000: smaller than most records; 5000 and 6007: a chunk and part of the next one (moved)
  for (size_t read_bytes : {size_t(0), size_t(13), size_t(1000), size_t(5000), size_t(6007), size_t(65536)}) {
    std::string err;
    const auto got = read_file(p, read_bytes, &err);
    EXPECT_EQ(err, mem_err) << what << ", reads of " << read_bytes;
    ASSERT_EQ(got.size(), mem.size()) << what << ", reads of " << read_bytes;
    for (size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i].topic, mem[i].topic) << what << " " << i;
      ASSERT_EQ(got[i].t, mem[i].t) << what << " " << i;
      ASSERT_EQ(got[i].data, mem[i].data) << what << " " << i;
    }
  }
}

void expect_damage_as_memory(const std::vector<uint8_t>& bytes, const std::string& what) {
  expect_file_as_memory(bytes, "whole", what + " whole");
  for (int tenths : {1, 3, 6, 9}) {  // truncated: cuts inside records and chunks
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(bytes.size() * size_t(tenths) / 10));
    expect_file_as_memory(cut, "cut", what + " cut at " + std::to_string(tenths) + "/10");
  }
  auto bad = bytes;  // a damaged byte in the middle (a chunk's data, a record header or length)
  for (size_t k = 0; k < 8; ++k) bad[bytes.size() / 2 + k] ^= 0x5A;
  expect_file_as_memory(bad, "bad", what + " damaged");
  auto len = bytes;  // a huge length early on (the first record after the magic / bag header)
  std::memset(&len[len[0] == '#' ? 13 : 9], 0xEE, 4);
  expect_file_as_memory(len, "len", what + " huge length");
}

TEST(FileReaders, BagFromTheFileAsFromMemory) {
  for (const std::string comp : {"none", "bz2", "lz4"}) {
    const auto bytes = write_mixed<BagWriter>(::testing::TempDir() + "/f.bag", comp, 3, [](BagWriter& w) {
      return std::pair{w.add_connection("/a", "std_msgs/String"), w.add_connection("/b", "ouster_ros/PacketMsg")};
    });
    std::string err;
    expect_mixed(read_file(::testing::TempDir() + "/f.bag", 29, &err), comp);
    EXPECT_EQ(err, "");
    expect_damage_as_memory(bytes, "bag " + comp);
  }
}

TEST(FileReaders, McapFromTheFileAsFromMemory) {
  for (const std::string comp : {"none", "zstd", "lz4"}) {
    const auto bytes = write_mixed<McapWriter>(::testing::TempDir() + "/f.mcap", comp, 5, [](McapWriter& w) {
      return std::pair{w.add_channel("/a", "std_msgs/msg/String"), w.add_channel("/b", "ouster_ros/msg/PacketMsg")};
    });
    std::string err;
    expect_mixed(read_file(::testing::TempDir() + "/f.mcap", 29, &err), comp);
    EXPECT_EQ(err, "");
    expect_damage_as_memory(bytes, "mcap " + comp);
  }
}

TEST(FileReaders, ShipInteriorBagFromTheFile) {
  const std::string path = data_dir() + "/recordings/ship-interior/2014-12-23-18-46-41_climbing_up_and_down_palette_facing_windows.bag";
  FPLOC_REQUIRE_FILE(path);
  const auto bytes = slurp(path);
  std::string mem_err, err;
  const auto mem = read_all(bytes.data(), bytes.size(), &mem_err, path);
  const auto got = read_file(path, 0, &err);
  EXPECT_EQ(err, mem_err);
  ASSERT_EQ(got.size(), mem.size());
  for (size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i].data, mem[i].data) << i;
}

}  // namespace
}  // namespace fploc::rec::test
