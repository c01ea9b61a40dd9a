// ROS 1 bags: the official ouster_ros driver's bag (-> one complete frame, equal to the pcap path),
// the ship-interior bag (bz2 chunks, LaserScan, tf, odometry), written bags (none/bz2/lz4), and
// truncated / corrupt / unindexed files.
#include <gtest/gtest.h>

#include <cstring>
#include <map>

#include "fploc/os1/packet.h"
#include "fploc/os1/pcap.h"
#include "fploc/recording/bag_writer.h"
#include "fploc/recording/ouster_packets.h"
#include "fploc/recording/recording.h"
#include "fploc/recording/ros_msgs.h"
#include "test_util.h"

using namespace fploc;
using namespace fploc::rec;
using namespace fploc::rec::test;

namespace {

const std::string kOusterBag = data_dir() + "/ouster/512x10_raw.bag";
std::string ship_bag() {
  const std::string dir = data_dir() + "/recordings/ship-interior";
  if (!std::filesystem::exists(dir)) return dir + "/missing.bag";
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".bag") return e.path().string();
  return dir + "/missing.bag";
}

// A classic pcap (Ethernet/IPv4/UDP) of the given datagrams, all to `port`.
std::vector<uint8_t> make_pcap(const std::vector<std::vector<uint8_t>>& payloads, uint16_t port) {
  std::vector<uint8_t> out;
  auto put = [&](const void* p, size_t n) { out.insert(out.end(), (const uint8_t*)p, (const uint8_t*)p + n); };
  const uint32_t gh[6] = {0xa1b2c3d4, 0x00040002, 0, 0, 65535, 1};
  put(gh, 24);
  uint32_t ts = 0;
  for (const auto& p : payloads) {
    const uint32_t len = uint32_t(14 + 20 + 8 + p.size());
    const uint32_t rh[4] = {++ts, 0, len, len};
    put(rh, 16);
    uint8_t eth[14] = {0};
    eth[12] = 0x08;
    put(eth, 14);
    uint8_t ip[20] = {0x45, 0};
    const uint16_t tot = uint16_t(20 + 8 + p.size());
    ip[2] = uint8_t(tot >> 8), ip[3] = uint8_t(tot);
    ip[8] = 64, ip[9] = 17;
    ip[12] = 10, ip[15] = 1, ip[16] = 10, ip[19] = 2;
    put(ip, 20);
    uint8_t udp[8] = {0x1d, 0x4e, uint8_t(port >> 8), uint8_t(port), uint8_t((8 + p.size()) >> 8), uint8_t(8 + p.size()), 0, 0};
    put(udp, 8);
    put(p.data(), p.size());
  }
  return out;
}

}  // namespace

TEST(Bag, OusterDriverBagGivesOneCompleteFrameEqualToPcapPath) {
  FPLOC_REQUIRE_FILE(kOusterBag);
  std::string err;
  auto r = open_recording(kOusterBag, &err);
  ASSERT_TRUE(r) << err;
  OusterPackets op;
  std::vector<Scan> frames;
  std::vector<std::vector<uint8_t>> lidar;
  std::string meta;
  int imu = 0;
  RawMessage m;
  while (r->next(m)) {
    const Connection& c = r->connections().at(m.conn);
    if (c.type == "std_msgs/String") {
      ASSERT_TRUE(decode_string(m.data, m.size, c.encoding, meta, &err)) << err;
      ASSERT_TRUE(op.set_metadata(meta, c.topic, &err)) << err;
      continue;
    }
    ASSERT_EQ(c.type, "ouster_ros/PacketMsg");
    const uint8_t* buf;
    size_t n;
    ASSERT_TRUE(decode_bytes(m.data, m.size, c.encoding, &buf, &n, &err)) << err;
    os1::ImuSample s;
    if (op.add(buf, n, m.time_ns, frames, &s)) {
      ++imu;
      EXPECT_NEAR(std::abs(s.accel_mps2[0]) + std::abs(s.accel_mps2[1]) + std::abs(s.accel_mps2[2]), 9.8, 3.0);
    } else if (n != os1::kImuPacketSize) {
      lidar.emplace_back(buf, buf + n);
    }
  }
  op.flush(frames);
  EXPECT_EQ(r->error(), "");
  EXPECT_EQ(imu, 10);
  EXPECT_EQ(lidar.size(), 32u);
  EXPECT_EQ(op.bad_packets, 0u);
  ASSERT_TRUE(op.info());
  ASSERT_EQ(frames.size(), 1u);
  const Scan& s = frames[0];
  EXPECT_EQ(s.height, op.info()->pixels_per_column);  // pixels per column from the bag's metadata
  EXPECT_EQ(s.height, 128);
  EXPECT_EQ(s.width, 512);
  EXPECT_EQ(s.missing_columns, 0);
  size_t valid = 0;
  for (uint32_t v : s.range_mm) valid += v != 0;
  EXPECT_GT(valid, s.range_mm.size() / 3);

  // The same packets through the pcap path (PcapReader -> FrameAssembler) give the same frame.
  const auto pcap = make_pcap(lidar, 7502);
  os1::PcapReader pr;
  ASSERT_TRUE(pr.open_memory(pcap.data(), pcap.size())) << pr.error();
  os1::FrameAssembler fa(os1::parse_metadata(meta));
  std::vector<Scan> pf;
  os1::UdpDatagram d;
  while (pr.next(d)) fa.add_packet(d.data, d.size, pf);
  fa.flush(pf);
  ASSERT_EQ(pf.size(), 1u);
  EXPECT_EQ(pf[0].frame_id, s.frame_id);
  EXPECT_EQ(pf[0].range_mm, s.range_mm);
  EXPECT_EQ(pf[0].reflectivity, s.reflectivity);
  EXPECT_EQ(pf[0].column_utime, s.column_utime);
}

TEST(Bag, ShipInteriorBz2LaserScanTfOdometry) {
  const std::string path = ship_bag();
  FPLOC_REQUIRE_FILE(path);
  std::string err;
  auto r = open_recording(path, &err);
  ASSERT_TRUE(r) << err;
  std::map<std::string, int> count;
  int tf_transforms = 0, odom = 0;
  RawMessage m;
  size_t beams_front = 0;
  while (r->next(m)) {
    const Connection& c = r->connections().at(m.conn);
    ++count[c.topic];
    if (c.type == "sensor_msgs/LaserScan") {
      LaserScan l;
      ASSERT_TRUE(decode(m.data, m.size, c.encoding, l, &err)) << err;
      EXPECT_GT(l.ranges.size(), 100u);
      EXPECT_NEAR(l.angle_min + l.angle_increment * (l.ranges.size() - 1), l.angle_max, std::abs(l.angle_increment) * 1.01);
      if (c.topic == "/guardian/laser_tilt_front") beams_front = l.ranges.size();
    } else if (c.type == "tf2_msgs/TFMessage") {
      std::vector<Transform> ts;
      ASSERT_TRUE(decode_tf(m.data, m.size, c.encoding, ts, &err)) << err;
      for (const auto& t : ts) EXPECT_NEAR(t.q[0] * t.q[0] + t.q[1] * t.q[1] + t.q[2] * t.q[2] + t.q[3] * t.q[3], 1.0, 1e-3);
      tf_transforms += int(ts.size());
    } else if (c.type == "nav_msgs/Odometry") {
      Odometry o;
      ASSERT_TRUE(decode(m.data, m.size, c.encoding, o, &err)) << err;
      ++odom;
    }
  }
  EXPECT_EQ(r->error(), "");
  EXPECT_EQ(count["/guardian/laser_tilt_front"], 421);
  EXPECT_EQ(count["/guardian/laser_horizontal_back"], 418);
  EXPECT_EQ(count["/tf"], 9358);
  EXPECT_EQ(odom, 839);
  EXPECT_GT(tf_transforms, 9358);
  EXPECT_GT(beams_front, 0u);
}

TEST(Bag, TruncatedFileKeepsWhatCameBefore) {
  const std::string path = ship_bag();
  FPLOC_REQUIRE_FILE(path);
  const auto bytes = slurp(path);
  std::string err;
  const auto all = read_all(bytes.data(), bytes.size(), &err);
  ASSERT_EQ(err, "");
  const size_t cut = bytes.size() * 6 / 10;
  const auto part = read_all(bytes.data(), cut, &err, "cut.bag");
  EXPECT_NE(err.find("cut.bag: record at byte "), std::string::npos) << err;
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;
  ASSERT_GT(part.size(), 1000u);
  ASSERT_LT(part.size(), all.size());
  for (size_t i = 0; i < part.size(); ++i) {
    ASSERT_EQ(part[i].topic, all[i].topic);
    ASSERT_EQ(part[i].data, all[i].data);
  }
}

// Cut at a record boundary before the index (a copy stopped between two chunks, or right after the bag header):
// no record is cut in two, but the bag header's index_pos lies past the end, so messages are missing. One error
// saying so, after every message before the cut; a bag of only the magic line is truncated too.
TEST(Bag, CutBetweenRecordsBeforeTheIndexIsTruncated) {
  const std::string path = ship_bag();
  FPLOC_REQUIRE_FILE(path);
  const auto bytes = slurp(path);
  std::string err;
  const auto all = read_all(bytes.data(), bytes.size(), &err);
  ASSERT_EQ(err, "");
  // Record boundaries: after the bag header (byte 13 + its record) and after the second chunk record.
  std::vector<size_t> ends;
  for (size_t pos = 13; pos + 8 <= bytes.size();) {
    uint32_t hl, dl;
    std::memcpy(&hl, &bytes[pos], 4);
    std::memcpy(&dl, &bytes[pos + 4 + hl], 4);
    pos += 8 + size_t(hl) + dl;
    ends.push_back(pos);
  }
  ASSERT_GT(ends.size(), 10u);
  for (const size_t cut : {ends[0], ends[3]}) {
    const auto part = read_all(bytes.data(), cut, &err, "cut.bag");
    EXPECT_NE(err.find("cut.bag: "), std::string::npos) << cut << ": " << err;
    EXPECT_NE(err.find("truncated"), std::string::npos) << cut << ": " << err;
    ASSERT_LT(part.size(), all.size());
    for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i].data, all[i].data);
  }
  const auto none = read_all(bytes.data(), 13, &err, "magic.bag");
  EXPECT_TRUE(none.empty());
  EXPECT_NE(err.find("magic.bag: "), std::string::npos) << err;
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;
  // Cut inside the magic line: truncated, not "version 2.0 is not supported".
  for (const size_t n : {size_t(9), size_t(12)}) {
    EXPECT_TRUE(read_all(bytes.data(), n, &err, "short.bag").empty());
    EXPECT_NE(err.find("short.bag: "), std::string::npos) << err;
    EXPECT_NE(err.find("truncated"), std::string::npos) << n << ": " << err;
    EXPECT_EQ(err.find("not supported"), std::string::npos) << n << ": " << err;
  }
  // The same for the MCAP magic, and an empty file says so.
  const uint8_t mcap[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  EXPECT_TRUE(read_all(mcap, 7, &err, "short.mcap").empty());
  EXPECT_NE(err.find("short.mcap: "), std::string::npos) << err;
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;
  EXPECT_TRUE(read_all(mcap, 0, &err, "empty.bag").empty());
  EXPECT_NE(err.find("empty.bag: empty file"), std::string::npos) << err;
}

TEST(Bag, WrittenBagsAllCompressionsAndDamage) {
  const std::string dir = ::testing::TempDir();
  for (const std::string comp : {"none", "bz2", "lz4"}) {
    const std::string p = dir + "/w_" + comp + ".bag";
    const auto bytes = write_mixed<BagWriter>(p, comp, 1, [](BagWriter& w) {
      return std::pair{w.add_connection("/a", "std_msgs/String"), w.add_connection("/b", "ouster_ros/PacketMsg")};
    });
    std::string err;
    const auto msgs = read_all(bytes.data(), bytes.size(), &err, p);
    EXPECT_EQ(err, "") << comp;
    expect_mixed(msgs, comp);
    // Unindexed (a recorder killed before writing the index): everything reads.
    uint64_t index_pos;
    const auto* h = bytes.data() + 13 + 4;
    const void* f = memmem(h, 200, "index_pos=", 10);
    ASSERT_TRUE(f);
    std::memcpy(&index_pos, static_cast<const uint8_t*>(f) + 10, 8);
    const auto unindexed = read_all(bytes.data(), size_t(index_pos), &err);
    EXPECT_EQ(err, "");
    EXPECT_EQ(unindexed.size(), size_t(kMixedMessages));
    if (comp != "none") {
      // A damaged compressed chunk: one error naming the chunk and its byte offset.
      auto bad = bytes;
      bad[4096 + 200] ^= 0x5A;
      bad[4096 + 201] ^= 0xA5;
      const auto some = read_all(bad.data(), bad.size(), &err, "bad.bag");
      EXPECT_NE(err.find("bad.bag: chunk at byte 4096 (" + comp + ")"), std::string::npos) << err;
      EXPECT_LT(some.size(), size_t(kMixedMessages));

      // A damaged later chunk (decompressed ahead, on the second thread, while the earlier ones are
      // read): the same one error naming that chunk, after every message of the chunks before it.
      std::vector<size_t> chunk_at, chunk_mid;  // chunk records: offset, and the middle of their data
      for (size_t pos = 13; pos + 8 <= bytes.size();) {
        uint32_t hl, dl;
        std::memcpy(&hl, &bytes[pos], 4);
        std::memcpy(&dl, &bytes[pos + 4 + hl], 4);
        if (memmem(&bytes[pos + 4], hl, "op=\x05", 4)) chunk_at.push_back(pos), chunk_mid.push_back(pos + 8 + hl + dl / 2);
        pos += 8 + size_t(hl) + dl;
      }
      ASSERT_GE(chunk_at.size(), 4u) << comp;
      auto bad3 = bytes;
      for (size_t k = 0; k < 8; ++k) bad3[chunk_mid[2] + k] ^= 0x5A;
      const auto before = read_all(bad3.data(), bad3.size(), &err, "bad3.bag");
      EXPECT_NE(err.find("bad3.bag: chunk at byte " + std::to_string(chunk_at[2]) + " (" + comp + ")"), std::string::npos) << err;
      ASSERT_GT(before.size(), 0u);
      ASSERT_LT(before.size(), size_t(kMixedMessages));
      for (size_t i = 0; i < before.size(); ++i) EXPECT_EQ(before[i].data, msgs[i].data) << i;
      const auto upto2 = read_all(bytes.data(), chunk_at[2], &err);  // the file cut right before that chunk
      EXPECT_EQ(before.size(), upto2.size()) << comp;
    }
  }
}

// The file ends inside an uncompressed chunk (or the chunk's length is damaged): the chunk's whole records are read
// (they were all lost: "0 messages read"), then one error naming the chunk, the file's size and how many of its
// messages were read. A compressed chunk cut short cannot be decompressed: the error says so. A corrupt bz2 chunk
// says what bz2's error code means.
TEST(Bag, CutInsideAChunkKeepsItsWholeRecords) {
  const std::string dir = ::testing::TempDir();
  for (const std::string comp : {"none", "bz2"}) {
    const auto bytes = write_mixed<BagWriter>(dir + "/c_" + comp + ".bag", comp, 1, [](BagWriter& w) {
      return std::pair{w.add_connection("/a", "std_msgs/String"), w.add_connection("/b", "ouster_ros/PacketMsg")};
    });
    std::vector<size_t> chunk_at, chunk_end;
    for (size_t pos = 13; pos + 8 <= bytes.size();) {
      uint32_t hl, dl;
      std::memcpy(&hl, &bytes[pos], 4);
      std::memcpy(&dl, &bytes[pos + 4 + hl], 4);
      if (memmem(&bytes[pos + 4], hl, "op=\x05", 4)) chunk_at.push_back(pos), chunk_end.push_back(pos + 8 + hl + dl);
      pos += 8 + size_t(hl) + dl;
    }
    ASSERT_GE(chunk_at.size(), 4u);
    std::string err;
    const auto all = read_all(bytes.data(), bytes.size(), &err);
    const auto upto2 = read_all(bytes.data(), chunk_at[2], &err);
    const auto upto3 = read_all(bytes.data(), chunk_end[2], &err);
    ASSERT_LT(upto2.size(), upto3.size());
    const size_t cut = (chunk_at[2] + chunk_end[2]) / 2;  // inside the third chunk's data
    const auto part = read_all(bytes.data(), cut, &err, "cut.bag");
    const std::string what = "cut.bag: record at byte " + std::to_string(chunk_at[2]) + ": chunk (" + comp + ") of ";
    EXPECT_EQ(err.find(what), 0u) << err;
    EXPECT_NE(err.find("runs past the end of the file (file size " + std::to_string(cut) + " B; file truncated"), std::string::npos) << err;
    if (comp == "none") {
      EXPECT_GT(part.size(), upto2.size());  // some of the cut chunk's messages
      EXPECT_LT(part.size(), upto3.size());
      EXPECT_NE(err.find("; the chunk's " + std::to_string(part.size() - upto2.size()) + " whole messages before the cut were read"),
                std::string::npos) << err;
      // Its length damaged in a whole file: not truncated; every message still read.
      auto bad = bytes;
      uint32_t hl;
      std::memcpy(&hl, &bad[chunk_at[2]], 4);
      const uint32_t huge = 0xFFFFFFF0u;
      std::memcpy(&bad[chunk_at[2] + 4 + hl], &huge, 4);
      const auto got = read_all(bad.data(), bad.size(), &err, "len.bag");
      EXPECT_NE(err.find("len.bag: record at byte " + std::to_string(chunk_at[2]) + ": chunk (none) of 4294967280 B runs past the end of the file (file size " +
                         std::to_string(bad.size()) + " B; the file is not short"), std::string::npos) << err;
      EXPECT_NE(err.find("the length is damaged"), std::string::npos) << err;
      EXPECT_GE(got.size(), upto3.size());
      for (size_t i = 0; i < got.size() && i < all.size(); ++i) EXPECT_EQ(got[i].data, all[i].data) << i;
    } else {
      EXPECT_EQ(part.size(), upto2.size());
      EXPECT_NE(err.find("a cut compressed chunk cannot be decompressed, its messages are lost"), std::string::npos) << err;
      // Its stream CRC (the last bytes of the bz2 data) damaged: bz2's code and what it means.
      auto bad = bytes;
      bad[chunk_end[2] - 2] ^= 0x01;
      read_all(bad.data(), bad.size(), &err, "bad.bag");
      EXPECT_NE(err.find("bad.bag: chunk at byte " + std::to_string(chunk_at[2]) + " (bz2): bz2 error -4 (BZ_DATA_ERROR: the compressed data is corrupt)"),
                std::string::npos) << err;
    }
    for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i].data, all[i].data) << i;
  }
}

TEST(Bag, NotABag) {
  const std::string s = "#ROSBAG V1.2\nxxxxxxxx";
  std::string err;
  EXPECT_FALSE(open_recording_memory(reinterpret_cast<const uint8_t*>(s.data()), s.size(), "old.bag", &err));
  EXPECT_NE(err.find("old.bag: ROS bag version 1.2 is not supported"), std::string::npos) << err;
  EXPECT_FALSE(open_recording_memory(reinterpret_cast<const uint8_t*>("hello"), 5, "x", &err));
  EXPECT_NE(err.find("neither"), std::string::npos);
  // A directory given as the recording: said so (it was "mmap: No such device").
  const std::string dir = ::testing::TempDir();
  EXPECT_FALSE(open_recording(dir, &err));
  EXPECT_EQ(err.rfind(dir + ": is a directory", 0), 0u) << err;
}
