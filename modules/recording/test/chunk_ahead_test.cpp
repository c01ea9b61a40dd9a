// ChunkAhead: the result of a chunk decompressed ahead is the sequential one whether the worker has
// finished it, is running it, or has not started it (the reader takes it back); a job for another chunk
// is dropped; a damaged chunk gives decompress()'s error; destruction with a job queued returns.
#include <gtest/gtest.h>

#include <isa-l/crc.h>

#include <chrono>
#include <thread>

#include "../src/chunk_ahead.h"
#include "fploc/recording/decompress.h"

namespace fploc::rec {
namespace {

TEST(ChunkAhead, SameResultWhateverTheWorkerDid) {
  std::vector<uint8_t> raw(300000);
  for (size_t i = 0; i < raw.size(); ++i) raw[i] = uint8_t((i * 2654435761u) >> 13);
  const uint32_t crc = crc32_gzip_refl(0, raw.data(), raw.size());
  for (const std::string method : {"zstd", "lz4", "bz2"}) {
    const auto z = compress(method, raw.data(), raw.size());
    ASSERT_FALSE(z.empty());
    ChunkAhead a;
    std::vector<uint8_t> out;
    for (int wait_ms : {0, 0, 30, 1, 30}) {
      ASSERT_FALSE(a.pending());
      a.start({size_t(100 + wait_ms), method, z.data(), z.size(), raw.size(), true});
      EXPECT_TRUE(a.pending());
      if (wait_ms) std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms));
      ChunkAhead::Result r;
      ASSERT_TRUE(a.take(size_t(100 + wait_ms), out, r)) << method;
      EXPECT_EQ(r.error, "");
      EXPECT_TRUE(r.has_crc);
      EXPECT_EQ(r.crc, crc);
      EXPECT_TRUE(out == raw) << method << " wait " << wait_ms;
    }
    // A job for another chunk is dropped (and nothing is pending after).
    a.start({7, method, z.data(), z.size(), raw.size(), false});
    ChunkAhead::Result r;
    EXPECT_FALSE(a.take(8, out, r));
    EXPECT_FALSE(a.pending());
    // A damaged chunk: decompress()'s error, as the sequential path gives it.
    auto bad = z;
    bad.resize(bad.size() / 2);
    std::vector<uint8_t> seq;
    const std::string want = decompress(method, bad.data(), bad.size(), raw.size(), seq);
    ASSERT_NE(want, "");
    a.start({9, method, bad.data(), bad.size(), raw.size(), true});
    ASSERT_TRUE(a.take(9, out, r));
    EXPECT_EQ(r.error, want);
    EXPECT_FALSE(r.has_crc);
    // Destroyed with a job queued or running: returns.
    a.start({10, method, z.data(), z.size(), raw.size(), false});
  }
}

}  // namespace
}  // namespace fploc::rec
