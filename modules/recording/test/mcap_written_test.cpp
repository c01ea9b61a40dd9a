// MCAP files written by McapWriter (none/zstd/lz4 chunks, CRCs) read back: every message, in order; a
// damaged later chunk (decompressed ahead on the second thread while the earlier ones are read) and a
// chunk whose recorded CRC does not match give the one sequential error naming that chunk, after exactly
// the messages of the chunks before it; a byte outside every chunk's records fails the data section's CRC.
#include <gtest/gtest.h>

#include <cstring>

#include "fploc/recording/mcap_writer.h"
#include "fploc/recording/recording.h"
#include "test_util.h"

namespace fploc::rec::test {
namespace {

// Top-level Chunk records: (offset, offset of the middle of their compressed records).
std::vector<std::pair<size_t, size_t>> chunks_of(const std::vector<uint8_t>& b) {
  std::vector<std::pair<size_t, size_t>> out;
  for (size_t pos = 8; pos + 9 <= b.size();) {
    uint64_t len;
    std::memcpy(&len, &b[pos + 1], 8);
    if (b[pos] == 0x06) out.push_back({pos, pos + 9 + len - (len - 40) / 2});
    if (b[pos] == 0x02) break;
    pos += 9 + len;
  }
  return out;
}

TEST(McapWritten, ManyChunksReadAheadAndDamage) {
  const std::string dir = ::testing::TempDir();
  for (const std::string comp : {"none", "zstd", "lz4"}) {
    const std::string p = dir + "/w_" + comp + ".mcap";
    const auto bytes = write_mixed<McapWriter>(p, comp, 7, [](McapWriter& w) {
      return std::pair{w.add_channel("/a", "std_msgs/msg/String"), w.add_channel("/b", "ouster_ros/msg/PacketMsg")};
    });
    std::string err;
    const auto msgs = read_all(bytes.data(), bytes.size(), &err, p);
    EXPECT_EQ(err, "") << comp;
    expect_mixed(msgs, comp);
    const auto chunks = chunks_of(bytes);
    ASSERT_GE(chunks.size(), 4u) << comp;
    const std::string third = "chunk at byte " + std::to_string(chunks[2].first) + " (" + (comp == "none" ? "none" : comp) + ")";
    const auto upto2 = read_all(bytes.data(), chunks[2].first, &err);  // the file cut right before that chunk

    // The third chunk's recorded CRC-32 (after start, end, size) changed: caught with the CRC the
    // worker computed (compressed) or here (none).
    auto badcrc = bytes;
    badcrc[chunks[2].first + 9 + 24] ^= 0x01;
    auto before = read_all(badcrc.data(), badcrc.size(), &err, "crc.mcap");
    EXPECT_EQ(err.find("crc.mcap: " + third + ": CRC-32 of the"), 0u) << err;
    EXPECT_EQ(before.size(), upto2.size()) << comp;

    // A byte that no chunk CRC covers (the third chunk's message_start_time) damaged: every message is
    // read, then the data section's CRC (kept as the records go by, an uncompressed chunk's records
    // combined from its own CRC) names the Data End record.
    auto badhdr = bytes;
    badhdr[chunks[2].first + 9] ^= 0x10;
    const auto all = read_all(badhdr.data(), badhdr.size(), &err, "hdr.mcap");
    EXPECT_EQ(err.find("hdr.mcap: data section (bytes 0.."), 0u) << comp << ": " << err;
    EXPECT_NE(err.find("(file damaged)"), std::string::npos) << err;
    EXPECT_EQ(all.size(), msgs.size()) << comp;

    if (comp == "none") continue;
    // Its compressed bytes damaged: the decompressor or the CRC catches it, naming that chunk.
    auto bad3 = bytes;
    for (size_t k = 0; k < 8; ++k) bad3[chunks[2].second + k] ^= 0x5A;
    before = read_all(bad3.data(), bad3.size(), &err, "bad3.mcap");
    EXPECT_EQ(err.find("bad3.mcap: " + third + ": "), 0u) << err;
    ASSERT_EQ(before.size(), upto2.size()) << comp;
    for (size_t i = 0; i < before.size(); ++i) EXPECT_EQ(before[i].data, msgs[i].data) << i;
  }
}

// The file ends inside an uncompressed chunk: its whole records are read (they were lost), then one error naming the
// chunk and the file's size; a compressed chunk cut short cannot be decompressed (said so); a damaged compression
// name is printed escaped (it was printed as raw bytes).
TEST(McapWritten, CutInsideAChunkKeepsItsWholeRecords) {
  const std::string dir = ::testing::TempDir();
  for (const std::string comp : {"none", "zstd"}) {
    const auto bytes = write_mixed<McapWriter>(dir + "/c_" + comp + ".mcap", comp, 7, [](McapWriter& w) {
      return std::pair{w.add_channel("/a", "std_msgs/msg/String"), w.add_channel("/b", "ouster_ros/msg/PacketMsg")};
    });
    const auto chunks = chunks_of(bytes);
    ASSERT_GE(chunks.size(), 4u);
    std::string err;
    const auto all = read_all(bytes.data(), bytes.size(), &err);
    const auto upto2 = read_all(bytes.data(), chunks[2].first, &err);
    const auto upto3 = read_all(bytes.data(), chunks[3].first, &err);
    const size_t cut = chunks[2].second;  // the middle of the third chunk's records
    const auto part = read_all(bytes.data(), cut, &err, "cut.mcap");
    const std::string what = "cut.mcap: chunk at byte " + std::to_string(chunks[2].first) + " (" + comp + "): length ";
    EXPECT_EQ(err.find(what), 0u) << err;
    EXPECT_NE(err.find("runs past the end of the file (file size " + std::to_string(cut) + " B; file truncated"), std::string::npos) << err;
    if (comp == "none") {
      EXPECT_GT(part.size(), upto2.size());
      EXPECT_LT(part.size(), upto3.size());
      EXPECT_NE(err.find("; the chunk's " + std::to_string(part.size() - upto2.size()) + " whole messages before the cut were read"),
                std::string::npos) << err;
    } else {
      EXPECT_EQ(part.size(), upto2.size());
      EXPECT_NE(err.find("a cut compressed chunk cannot be decompressed"), std::string::npos) << err;
      // The compression name's first byte damaged: printed escaped.
      auto bad = bytes;
      bad[chunks[2].first + 9 + 28 + 4] = 0xE9;  // after start, end, size, crc and the name's length
      read_all(bad.data(), bad.size(), &err, "comp.mcap");
      EXPECT_NE(err.find("comp.mcap: chunk at byte " + std::to_string(chunks[2].first) + " (\\xe9std): unsupported compression '\\xe9std'"),
                std::string::npos) << err;
    }
    for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i].data, all[i].data) << i;
  }
}

}  // namespace
}  // namespace fploc::rec::test
