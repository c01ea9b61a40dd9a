// Perception nodes over LCM (each case in its own network namespace, see CMakeLists.txt): fploc-segmenter,
// fploc-segmenter-ransac and fploc-features as real processes started from perception_it.pbtxt. Good
// simulated OS-1-64 scans in -> segments and features out; bad scans (empty, all-zero ranges, non-finite
// beam angles, too few beams, truncated pixel arrays, undecodable bytes) and bad segments -> a status in
// the output message and the error in the node's telemetry (node_status_t.last_error); every node stays
// up and handles the next good message.
#include <fcntl.h>
#include <fploc/features_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/scan_t.hpp>
#include <fploc/segments_t.hpp>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../support/process.h"
#include "fploc/adapters/scan_t.h"
#include "fploc/sim/simulator.h"

namespace fs = std::filesystem;
using namespace fploc::test;

namespace {

const std::string kRoot = root();
const std::string kGraph = kRoot + "/tests/perception/perception_it.pbtxt";
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";  // as in the graph

// Everything the test hears on the bus.
struct Listener {
  lcm::LCM lcm{kUrl};
  std::map<std::string, std::vector<fploc::segments_t>> segments;  // by channel
  std::vector<fploc::features_t> features;
  std::vector<fploc::node_status_t> telemetry;
  Listener() {
    lcm.subscribe("IT_SEG_RINGS", &Listener::on_seg, this);
    lcm.subscribe("IT_SEG_RANSAC", &Listener::on_seg, this);
    lcm.subscribe("IT_FEATURES", &Listener::on_feat, this);
    lcm.subscribe("FPLOC_TELEMETRY", &Listener::on_tel, this);
  }
  void on_seg(const lcm::ReceiveBuffer*, const std::string& ch, const fploc::segments_t* m) { segments[ch].push_back(*m); }
  void on_feat(const lcm::ReceiveBuffer*, const std::string&, const fploc::features_t* m) { features.push_back(*m); }
  void on_tel(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) { telemetry.push_back(*m); }
  // Pumps until pred() holds (true) or the timeout passes (false).
  bool until(double timeout_s, const std::function<bool()>& pred) {
    const double t0 = now_s();
    while (!pred()) {
      if (now_s() - t0 > timeout_s) return false;
      lcm.handleTimeout(20);
    }
    return true;
  }
  const fploc::segments_t* seg_for(const std::string& ch, int64_t scan_seq) const {
    auto it = segments.find(ch);
    if (it == segments.end()) return nullptr;
    for (const auto& m : it->second)
      if (m.scan_seq == scan_seq) return &m;
    return nullptr;
  }
  const fploc::features_t* feat_for(int64_t scan_seq) const {
    for (const auto& m : features)
      if (m.scan_seq == scan_seq) return &m;
    return nullptr;
  }
  // A heartbeat of `node` (from the node itself) received after index `from` whose last_error has `what`.
  bool error_reported(const std::string& node, const std::string& what, size_t from) const {
    for (size_t i = from; i < telemetry.size(); ++i)
      if (telemetry[i].node == node && telemetry[i].reporter == "node" &&
          telemetry[i].last_error.find(what) != std::string::npos)
        return true;
    return false;
  }
  std::string last_error(const std::string& node) const {
    for (size_t i = telemetry.size(); i-- > 0;)
      if (telemetry[i].node == node && telemetry[i].reporter == "node") return telemetry[i].last_error;
    return "(no heartbeat)";
  }
};

class PerceptionNodes : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = (fs::temp_directory_path() / ("fploc-perc-" + std::string(info->name()) + "-" + std::to_string(getpid())))
               .string();
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
    else std::cerr << "test files kept in " << dir_ << "\n";
  }
  Proc start(const std::string& exe, const std::string& node) {
    return Proc::spawn({bin(exe), "--graph", kGraph, "--node", node}, dir_, node);
  }
  // Waits for the first heartbeat of each node (its subscriptions are up by then).
  void wait_up(Listener& bus, const std::vector<std::pair<std::string, const Proc*>>& nodes) {
    for (const auto& [name, proc] : nodes) {
      const bool up = bus.until(15, [&] {
        for (const auto& t : bus.telemetry)
          if (t.node == name && t.reporter == "node") return true;
        return false;
      });
      ASSERT_TRUE(up) << name << " sent no heartbeat:\n" << slurp(proc->err_file);
    }
  }
  std::string dir_;
};

// Simulated OS-1-64 scans (real beams from ../shared when present) and the IMU samples of their sweep.
struct SimSource {
  fploc::sim::Simulator sim;
  static fploc::sim::SimulatorOptions options() {
    fploc::sim::SimulatorOptions o;
    o.scenario = "room-small-loop-medium";
    o.seed = 3;
    o.shared_dir = env("FPLOC_SHARED_DIR", FPLOC_SHARED_DIR);
    return o;
  }
  SimSource() : sim(fploc::FloorPlan{}, options()) {}
  fploc::scan_t scan(int k, int64_t seq) {
    fploc::sim::SimScan f;
    sim.frame(k, f);
    f.scan.seq = seq;
    fploc::scan_t m;
    fploc::adapters::to_msg(f.scan, m);
    return m;
  }
  std::vector<fploc::imu_t> imu(int k) const {
    std::vector<fploc::imu_t> out;
    const double t0 = sim.frame_time(k) - sim.options().t0_s, t1 = t0 + 1.0 / sim.options().rate_hz;
    for (const auto& s : sim.imu()) {
      if (s.t < t0 - 0.02 || s.t > t1 + 0.005) continue;
      fploc::imu_t m;
      m.utime = m.accel_utime = m.gyro_utime = int64_t(std::llround((sim.options().t0_s + s.t) * 1e6));
      m.seq = int64_t(out.size());
      for (int i = 0; i < 3; ++i) m.accel[i] = s.accel[i], m.gyro[i] = s.gyro[i];
      m.source = "sim";
      out.push_back(m);
    }
    return out;
  }
};

std::vector<uint8_t> encode(const fploc::scan_t& m) {
  std::vector<uint8_t> b(size_t(m.getEncodedSize()));
  m.encode(b.data(), 0, int(b.size()));
  return b;
}

// Wall points of a 6 x 8 m box room seen from (1, -0.5) at 1.2 m, 16 rings x 1024 columns, ring-major with
// increasing column: what the segmenter publishes for a clean room.
fploc::segments_t box_room_segments(int64_t seq) {
  fploc::segments_t m{};
  m.utime = 1700000000000000 + seq * 100000;
  m.seq = seq;
  m.scan_seq = seq;
  m.status = 0;
  m.ceiling_found = true;
  m.ceiling_plane[2] = -1;
  m.ceiling_plane[3] = 1.8;
  m.ground_found = true;
  m.ground_plane[2] = 1;
  m.ground_plane[3] = 1.2;
  m.roll = 0.01;
  m.pitch = -0.005;
  m.z = 1.2;
  m.roll_pitch_sigma = 0.001;
  m.z_sigma = 0.005;
  m.height = 16;
  m.width = 1024;
  const double ox = 1.0, oy = -0.5, hx = 3.0, hy = 4.0;
  for (int u = 0; u < 16; ++u) {
    const double elev = (-15.0 + 2.0 * u) * M_PI / 180;
    for (int c = 0; c < 1024; ++c) {
      const double a = 2 * M_PI * c / 1024, dx = std::cos(a), dy = std::sin(a);
      double t = std::numeric_limits<double>::infinity();
      if (dx > 1e-9) t = std::min(t, (hx - ox) / dx);
      if (dx < -1e-9) t = std::min(t, (-hx - ox) / dx);
      if (dy > 1e-9) t = std::min(t, (hy - oy) / dy);
      if (dy < -1e-9) t = std::min(t, (-hy - oy) / dy);
      m.x.push_back(float(t * dx));
      m.y.push_back(float(t * dy));
      m.z_pts.push_back(float(t * std::tan(elev)));
      m.range_m.push_back(float(t / std::cos(elev)));
      m.ring.push_back(int16_t(u));
      m.column.push_back(int16_t(c));
      m.t_offset_s.push_back(float(c * 0.1 / 1024));
    }
  }
  m.num_points = int32_t(m.x.size());
  return m;
}

}  // namespace

TEST_F(PerceptionNodes, SegmentersReportBadScansAndKeepRunning) {
  Listener bus;
  Proc rings = start("fploc-segmenter", "rings");
  Proc ransac = start("fploc-segmenter-ransac", "ransac");
  Proc features = start("fploc-features", "features");
  wait_up(bus, {{"rings", &rings}, {"ransac", &ransac}, {"features", &features}});
  if (HasFatalFailure()) return;
  SimSource src;
  auto publish_good = [&](int k, int64_t seq) {
    for (const auto& m : src.imu(k)) bus.lcm.publish("IT_IMU", &m);
    const auto s = src.scan(k, seq);
    bus.lcm.publish("IT_SCAN", &s);
  };
  auto expect_good = [&](int64_t seq, const std::string& when) {
    const bool got = bus.until(20, [&] {
      return bus.seg_for("IT_SEG_RINGS", seq) && bus.seg_for("IT_SEG_RANSAC", seq) && bus.feat_for(seq);
    });
    ASSERT_TRUE(got) << when << ": no segments/features for scan " << seq << "\nrings:\n" << slurp(rings.err_file)
                     << "\nransac:\n" << slurp(ransac.err_file) << "\nfeatures:\n" << slurp(features.err_file);
    const auto* r = bus.seg_for("IT_SEG_RINGS", seq);
    EXPECT_EQ(r->status, 0) << when << ": " << r->status_text;
    EXPECT_TRUE(r->ceiling_found) << when;
    EXPECT_GT(r->num_points, 10000) << when;
    ASSERT_EQ(r->t_offset_s.size(), size_t(r->num_points));
    for (float t : r->t_offset_s) {
      ASSERT_GE(t, 0.f) << when;
      ASSERT_LT(t, 0.1f) << when;  // inside the sweep (10 Hz)
    }
    EXPECT_NEAR(r->z, 1.2, 0.1) << when;  // the simulated tripod height
    const auto* q = bus.seg_for("IT_SEG_RANSAC", seq);
    EXPECT_TRUE(q->status == 0 || q->status == 1) << when << ": " << int(q->status) << " " << q->status_text;
    const auto* f = bus.feat_for(seq);
    EXPECT_EQ(f->status, 0) << when;
    EXPECT_GT(f->num_points, 100) << when;
    EXPECT_EQ(f->utime, r->utime);
  };

  publish_good(10, 1);
  expect_good(1, "first good scan");
  if (HasFatalFailure()) return;

  struct Bad {
    std::string name;
    std::function<std::vector<uint8_t>(int64_t seq)> make;
    int status;            // expected segments_t.status (-1: undecodable, no message)
    std::string text;      // in segments_t.status_text and in the segmenters' last_error
  };
  const std::vector<Bad> cases = {
      {"empty scan",
       [&](int64_t seq) {
         fploc::scan_t m{};
         m.seq = seq;
         m.sensor = "test";
         return encode(m);
       },
       2, "empty scan"},
      {"all-zero ranges",
       [&](int64_t seq) {
         auto m = src.scan(11, seq);
         std::fill(m.range_mm.begin(), m.range_mm.end(), 0);
         return encode(m);
       },
       3, "no valid returns"},
      {"all-NaN beam angles",
       [&](int64_t seq) {
         auto m = src.scan(11, seq);
         std::fill(m.beam_altitude_deg.begin(), m.beam_altitude_deg.end(), std::nanf(""));
         std::fill(m.beam_azimuth_deg.begin(), m.beam_azimuth_deg.end(), std::nanf(""));
         return encode(m);
       },
       2, "not finite"},
      {"wrong beam count (2 beams)",
       [&](int64_t seq) {
         auto m = src.scan(11, seq);
         m.height = 2;
         m.num_pixels = 2 * m.width;
         m.range_mm.resize(size_t(m.num_pixels));
         m.signal.resize(size_t(m.num_pixels));
         m.reflectivity.resize(size_t(m.num_pixels));
         m.beam_altitude_deg.resize(2);
         m.beam_azimuth_deg.resize(2);
         m.pixel_shift_by_row.resize(2);
         return encode(m);
       },
       2, "too few beams"},
      {"truncated pixel arrays",
       [&](int64_t seq) {
         auto m = src.scan(11, seq);
         m.num_pixels -= 1000;
         m.range_mm.resize(size_t(m.num_pixels));
         m.signal.resize(size_t(m.num_pixels));
         m.reflectivity.resize(size_t(m.num_pixels));
         return encode(m);
       },
       2, "num_pixels != height*width"},
      {"undecodable bytes (message cut short)",
       [&](int64_t seq) {
         auto b = encode(src.scan(11, seq));
         b.resize(b.size() / 3);
         return b;
       },
       -1, "undecodable"},
  };
  int64_t seq = 2;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const size_t tel_from = bus.telemetry.size();
    const auto bytes = c.make(seq);
    bus.lcm.publish("IT_SCAN", bytes.data(), unsigned(bytes.size()));
    if (c.status >= 0) {
      ASSERT_TRUE(bus.until(10, [&] { return bus.seg_for("IT_SEG_RINGS", seq) && bus.seg_for("IT_SEG_RANSAC", seq); }))
          << "no segments message for the bad scan";
      for (const char* ch : {"IT_SEG_RINGS", "IT_SEG_RANSAC"}) {
        const auto* s = bus.seg_for(ch, seq);
        EXPECT_EQ(s->status, c.status) << ch << ": " << s->status_text;
        EXPECT_NE(s->status_text.find(c.text), std::string::npos) << ch << ": '" << s->status_text << "'";
        EXPECT_FALSE(s->ceiling_found) << ch;
        EXPECT_EQ(s->num_points, 0) << ch;
      }
      // Downstream gets the status too: features mark the frame BAD_INPUT (not their own error).
      ASSERT_TRUE(bus.until(10, [&] { return bus.feat_for(seq) != nullptr; })) << "no features message";
      EXPECT_EQ(bus.feat_for(seq)->status, 2);
      EXPECT_EQ(bus.feat_for(seq)->num_points, 0);
    }
    for (const char* node : {"rings", "ransac"}) {
      EXPECT_TRUE(bus.until(5, [&] { return bus.error_reported(node, c.text, tel_from); }))
          << node << " telemetry last_error: '" << bus.last_error(node) << "'";
    }
    ++seq;
  }
  EXPECT_EQ(bus.last_error("features"), "") << "upstream bad scans are not the feature extractor's errors";

  // Still running, and a good scan is handled as before.
  EXPECT_TRUE(rings.alive());
  EXPECT_TRUE(ransac.alive());
  EXPECT_TRUE(features.alive());
  publish_good(12, seq);
  expect_good(seq, "good scan after the bad ones");
  EXPECT_TRUE(rings.alive() && ransac.alive() && features.alive());
}

TEST_F(PerceptionNodes, FeaturesReportBadSegmentsAndKeepRunning) {
  Listener bus;
  Proc features = start("fploc-features", "features");
  wait_up(bus, {{"features", &features}});
  if (HasFatalFailure()) return;
  auto expect_good = [&](int64_t seq) {
    ASSERT_TRUE(bus.until(10, [&] { return bus.feat_for(seq) != nullptr; })) << slurp(features.err_file);
    const auto* f = bus.feat_for(seq);
    EXPECT_EQ(f->status, 0);
    EXPECT_GT(f->num_points, 50);
    EXPECT_EQ(f->utime, 1700000000000000 + seq * 100000);
    int corners = 0;
    for (auto k : f->kind) corners += k == 0;
    EXPECT_GE(corners, 4);  // the room's corners, seen on several rings
    ASSERT_EQ(f->t_offset_s.size(), size_t(f->num_points));
    for (float t : f->t_offset_s) ASSERT_TRUE(t >= 0.f && t < 0.1f) << t;
  };
  {
    const auto m = box_room_segments(1);
    bus.lcm.publish("IT_SEG_RINGS", &m);
    expect_good(1);
    if (HasFatalFailure()) return;
  }
  struct Bad {
    std::string name;
    std::function<std::vector<uint8_t>(int64_t)> make;
    bool decodable;
    std::string text;  // in the features node's last_error
  };
  auto enc = [](const fploc::segments_t& m) {
    std::vector<uint8_t> b(size_t(m.getEncodedSize()));
    m.encode(b.data(), 0, int(b.size()));
    return b;
  };
  const std::vector<Bad> cases = {
      {"wall points not ring-major",
       [&](int64_t seq) {
         auto m = box_room_segments(seq);
         std::swap(m.ring.front(), m.ring.back());
         return enc(m);
       },
       true, "not ring-major"},
      {"non-finite roll",
       [&](int64_t seq) {
         auto m = box_room_segments(seq);
         m.roll = std::nan("");
         return enc(m);
       },
       true, "non-finite roll/pitch"},
      {"undecodable bytes",
       [&](int64_t seq) {
         auto b = enc(box_room_segments(seq));
         b.resize(b.size() / 2);
         return b;
       },
       false, "undecodable"},
  };
  int64_t seq = 2;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const size_t tel_from = bus.telemetry.size();
    const auto b = c.make(seq);
    bus.lcm.publish("IT_SEG_RINGS", b.data(), unsigned(b.size()));
    if (c.decodable) {
      ASSERT_TRUE(bus.until(10, [&] { return bus.feat_for(seq) != nullptr; })) << "no features message";
      EXPECT_EQ(bus.feat_for(seq)->status, 2);
      EXPECT_EQ(bus.feat_for(seq)->num_points, 0);
    }
    EXPECT_TRUE(bus.until(5, [&] { return bus.error_reported("features", c.text, tel_from); }))
        << "telemetry last_error: '" << bus.last_error("features") << "'";
    ++seq;
  }
  EXPECT_TRUE(features.alive());
  const auto m = box_room_segments(seq);
  bus.lcm.publish("IT_SEG_RINGS", &m);
  expect_good(seq);
  EXPECT_TRUE(features.alive());
}
