#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/ground_truth_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>

#include "model.h"
#include "push_hub.h"
#include "web_path.h"

using namespace fploc::dashboard;
using nlohmann::json;
namespace fs = std::filesystem;

static fploc::pose_t pose(int64_t t, double x, double y) {
  fploc::pose_t p{};
  p.utime = t;
  p.position[0] = x;
  p.position[1] = y;
  p.orientation[3] = 1;
  return p;
}
static fploc::ground_truth_t gt(int64_t t, double x, double y) {
  fploc::ground_truth_t g{};
  g.utime = t;
  g.position[0] = x;
  g.position[1] = y;
  g.orientation[3] = 1;
  return g;
}

TEST(DashboardModel, AteMatchesByUtimeInEitherOrder) {
  Model m;
  m.on_ground_truth(gt(1000000, 0, 0), 0, 0);
  m.on_pose(pose(1000000, 3, 4), 0, 0);   // error 5
  m.on_pose(pose(2000000, 1, 0), 0, 0);   // no GT yet
  EXPECT_EQ(m.ate_count(), 1u);
  m.on_ground_truth(gt(2000000, 0, 0), 0, 0);  // error 1 -> rmse sqrt((25+1)/2)
  EXPECT_EQ(m.ate_count(), 2u);
  EXPECT_NEAR(m.ate_rmse(), std::sqrt(13.0), 1e-9);
  m.on_pose(pose(1000000, 0, 0), 0, 0);  // the optimiser refines the first pose: error 0
  EXPECT_NEAR(m.ate_rmse(), std::sqrt(0.5), 1e-9);
  m.on_pose(pose(5000000, 0, 0), 0, 0);  // no GT within tolerance
  EXPECT_EQ(m.ate_count(), 2u);
  auto h = json::parse(m.history_json());
  EXPECT_EQ(h["est"].size(), 3u);  // the refined pose replaced its entry
  EXPECT_EQ(h["gt"].size(), 2u);
}

// A page opened mid-run draws the roll/pitch and rate plots from /api/history: the ground truth's rows carry
// roll, pitch and yaw (they had utime, x, y, z only), and the frame/pose rates of each tick are kept with the
// newest pose's time (they had no history).
TEST(DashboardModel, HistoryHasGroundTruthAttitudeAndRates) {
  Model m;
  auto g = gt(1000000, 1, 2);
  g.orientation[0] = std::sin(0.05);  // roll 0.1 rad
  g.orientation[3] = std::cos(0.05);
  m.on_ground_truth(g, 0.0, 0);
  m.on_pose(pose(1000000, 1, 2), 0.0, 0);
  m.on_pose(pose(1100000, 1, 2), 0.1, 0);
  m.tick(0.5, 0);
  m.on_pose(pose(1200000, 1, 2), 0.6, 0);
  m.tick(1.0, 0);
  auto h = json::parse(m.history_json());
  ASSERT_EQ(h["fields_gt"], json({"utime", "x", "y", "z", "roll", "pitch", "yaw"}));
  ASSERT_EQ(h["gt"].size(), 1u);
  EXPECT_NEAR(h["gt"][0][4].get<double>(), 0.1, 1e-6);
  EXPECT_NEAR(h["gt"][0][5].get<double>(), 0.0, 1e-6);
  ASSERT_EQ(h["fields_rates"], json({"utime", "frame_rate_hz", "pose_rate_hz"}));
  ASSERT_EQ(h["rates"].size(), 2u);
  EXPECT_EQ(h["rates"][0][0], 1100000);
  EXPECT_EQ(h["rates"][1][0], 1200000);
  EXPECT_GT(h["rates"][1][2].get<double>(), 0.0);
  EXPECT_EQ(json::parse(m.history_json(1150000))["rates"].size(), 1u);  // `since` applies
}

// The history keeps each pose's floor (the page draws only the trail on the floor it shows): the floor's name as
// the row's last field, null when the pose did not say.
TEST(DashboardModel, HistoryKeepsEachPosesFloor) {
  Model m;
  auto on = [&](int64_t t, const char* floor) {
    fploc::pose_t p = pose(t, 1, 2);
    p.floor = floor;
    m.on_pose(p, 0, 0);
  };
  on(1000000, "ground");
  on(2000000, "first");
  on(3000000, "");
  auto h = json::parse(m.history_json());
  ASSERT_EQ(h["fields_est"].back(), "floor");
  ASSERT_EQ(h["est"].size(), 3u);
  const size_t k = h["fields_est"].size() - 1;
  EXPECT_EQ(h["est"][0][k], "ground");
  EXPECT_EQ(h["est"][1][k], "first");
  EXPECT_TRUE(h["est"][2][k].is_null());
}

TEST(DashboardModel, NodeTurnsRedWhenSilentOrRestartingAndGreenAgain) {
  ModelConfig cfg;
  cfg.silent_after_s = 2.0;
  Model m(cfg);
  fploc::node_status_t s{};
  s.node = "matcher";
  s.state = "running";
  s.reporter = "node";
  m.on_status(s, 10.0);
  auto health = [&] { return json::parse(m.state_json())["nodes"]["nodes"][0]["health"].get<std::string>(); };
  EXPECT_EQ(health(), "ok");
  m.tick(11.9, 0);
  EXPECT_EQ(health(), "ok");
  m.tick(12.5, 0);
  EXPECT_EQ(health(), "bad");
  m.on_status(s, 13.0);
  EXPECT_EQ(health(), "ok");
  s.state = "restarting";
  s.reporter = "launcher";
  m.on_status(s, 13.5);
  EXPECT_EQ(health(), "bad");
}

// The launcher reports a remote node whose host is away as "waiting" with the host in last_error: a red row
// that names the host (it was "warn" with the bare word "waiting").
TEST(DashboardModel, ANodeWaitingForItsHostIsRedAndNamesTheHost) {
  Model m;
  fploc::node_status_t s{};
  s.node = "matcher";
  s.state = "waiting";
  s.reporter = "launcher";
  s.last_error = "waiting for host 'compute': not reachable with ssh (10.0.0.2): ssh: connect to host 10.0.0.2 port 22: "
                 "No route to host";
  m.on_status(s, 1.0);
  const auto n = json::parse(m.state_json())["nodes"]["nodes"][0];
  EXPECT_EQ(n["health"], "bad");
  EXPECT_EQ(n["state"], "waiting");
  EXPECT_EQ(n["reason"], s.last_error);
}

static fploc::port_stats_t input(const std::string& port, double rate_hz, double p50, double p99) {
  fploc::port_stats_t p{};
  p.port = port;
  p.channel = "FPLOC_" + port;
  p.rate_hz = rate_hz;
  p.latency_p50_ms = p50;
  p.latency_p99_ms = p99;
  return p;
}

TEST(DashboardModel, LatencyShownIsThatOfTheBusiestInput) {
  Model m;
  fploc::node_status_t s{};
  s.node = "matcher";
  s.state = "running";
  s.latency_p50_ms = 0.01;  // node-wide: dominated by the 100 Hz IMU
  s.latency_p99_ms = 3.9;
  s.ports = {input("imu", 100, 0.01, 0.02), input("features", 10, 3.5, 3.9), input("initial_pose", 0, 9, 9)};
  fploc::port_stats_t out{};
  out.port = "frame_pose";
  out.output = true;
  out.rate_hz = 10;
  s.ports.push_back(out);
  s.num_ports = int32_t(s.ports.size());
  m.on_status(s, 1.0);
  const auto n = json::parse(m.state_json())["nodes"]["nodes"][0];
  EXPECT_EQ(n["work_port"], "features");  // initial_pose is slower but received nothing this period
  EXPECT_DOUBLE_EQ(n["work_p50_ms"].get<double>(), 3.5);
  EXPECT_DOUBLE_EQ(n["work_p99_ms"].get<double>(), 3.9);
  EXPECT_DOUBLE_EQ(n["latency_p50_ms"].get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(n["ports"][0]["latency_p99_ms"].get<double>(), 0.02);

  s.ports = {out};  // a source: no input, the page falls back to the node-wide numbers
  s.num_ports = 1;
  m.on_status(s, 2.0);
  EXPECT_TRUE(json::parse(m.state_json())["nodes"]["nodes"][0]["work_port"].is_null());
}

TEST(DashboardModel, ExpectedNodeIsListedBeforeItsFirstHeartbeat) {
  Model m;  // silent_after_s = 2
  m.expect_node("optimizer", "fploc-optimizer", 0.0);
  auto node = [&] { return json::parse(m.state_json())["nodes"]["nodes"][0]; };
  m.tick(1.0, 0);
  EXPECT_EQ(node()["health"], "warn");
  m.tick(2.5, 0);
  EXPECT_EQ(node()["health"], "bad");
  EXPECT_TRUE(node()["age_s"].is_null());
  fploc::node_status_t s{};
  s.node = "optimizer";
  s.state = "running";
  m.on_status(s, 3.0);
  EXPECT_EQ(node()["health"], "ok");
}

// The launcher answers a refused control request (`fploc node restart nosuch`) with a node_status_t of state
// "rejected" under the requested name, for `fploc node` to print: that is no node, and no state of a node.
TEST(DashboardModel, ARejectedControlRequestIsNoNodeRow) {
  Model m;
  m.expect_node("optimizer", "fploc-optimizer", 0.0);
  fploc::node_status_t s{};
  s.node = "optimizer";
  s.state = "running";
  m.on_status(s, 0.5);
  fploc::node_status_t r{};
  r.node = "nosuch";
  r.state = "rejected";
  r.reporter = "launcher";
  r.last_error = "control: no running node named 'nosuch'";
  m.on_status(r, 1.0);
  r.node = "optimizer";  // a refused request about a node that runs leaves its row as it was
  m.on_status(r, 1.0);
  m.tick(1.2, 0);
  const auto nodes = json::parse(m.state_json())["nodes"]["nodes"];
  ASSERT_EQ(nodes.size(), 1u) << nodes.dump();
  EXPECT_EQ(nodes[0]["node"], "optimizer");
  EXPECT_EQ(nodes[0]["health"], "ok") << nodes.dump();
}

TEST(DashboardModel, FeaturesJsonIsValidAndDecimated) {
  fploc::features_t f{};
  f.scan_seq = 7;
  for (int i = 0; i < 1000; ++i) {
    f.x.push_back(float(i) * 0.01f);
    f.y.push_back(i == 3 ? NAN : 1.0f);
    f.kind.push_back(int8_t(i % 2));
    f.group.push_back(-1);
    f.t_offset_s.push_back(0.f);
  }
  f.num_points = 1000;
  auto j = json::parse(Model::features_json(f, 100, "null"));
  EXPECT_EQ(j["n"], 1000);
  EXPECT_LE(j["xy"].size() / 2, 100u);
  EXPECT_EQ(j["xy"].size() / 2, j["kind"].get<std::string>().size());
  // Inconsistent array sizes never read out of bounds.
  f.num_points = 5000;
  EXPECT_NO_THROW(json::parse(Model::features_json(f, 0, "null")));
}

TEST(DashboardPushHub, RateCappedPerStreamLatestValueOnly) {
  // Fake clock: poses every 2 ms for 0.5 s, the broadcaster asks whenever it is woken.
  PushHub hub;
  int wakeups = 0;
  hub.set_notify([&] { ++wakeups; });
  int pose_pushes = 0;
  std::string last;
  double next_due = 0;
  for (int i = 0; i < 250; ++i) {
    const double t = 0.002 * i;
    hub.set("pose", "{\"seq\":" + std::to_string(i) + "}");
    if (i % 50 == 0) hub.set("nodes", "[" + std::to_string(i) + "]");
    const std::string out = hub.take_due(t, 20, next_due);
    if (out.find("event: pose") != std::string::npos) {
      ++pose_pushes;
      EXPECT_EQ(out.find("event: pose"), out.rfind("event: pose"));  // one pose per push, never a queue
      last = out;
    }
    if (!out.empty()) continue;
    EXPECT_GT(next_due, t);  // held back: the broadcaster knows when to come back
    EXPECT_LE(next_due, t + 0.05 + 1e-9);
  }
  EXPECT_EQ(wakeups, 255);
  EXPECT_EQ(pose_pushes, 10);  // 20 Hz for 0.5 s
  // The newest pose (held back at the end) goes out once it is due; then nothing is due, nothing waits.
  EXPECT_NE(hub.take_due(1.0, 20, next_due).find("event: pose\ndata: {\"seq\":249}"), std::string::npos);
  EXPECT_EQ(hub.take_due(2.0, 20, next_due), "");
  EXPECT_TRUE(std::isinf(next_due));
  // A new client starts from the latest value of every stream.
  const std::string snap = hub.snapshot();
  EXPECT_NE(snap.find("event: pose\ndata: {\"seq\":249}\n\n"), std::string::npos) << snap;
  EXPECT_NE(snap.find("event: nodes\ndata: [200]"), std::string::npos) << snap;
  EXPECT_EQ(json::parse(hub.state_json())["pose"]["seq"], 249);
}

TEST(DashboardWebPath, RejectsTraversal) {
  const fs::path dir = fs::temp_directory_path() / ("fploc_web_" + std::to_string(getpid()));
  fs::create_directories(dir / "web" / "sub");
  std::ofstream(dir / "web" / "index.html") << "x";
  std::ofstream(dir / "web" / "sub" / "a.js") << "x";
  std::ofstream(dir / "web" / ".hidden") << "x";
  std::ofstream(dir / "secret.txt") << "x";
  fs::create_symlink(dir / "secret.txt", dir / "web" / "link.txt");
  const fs::path root = fs::canonical(dir / "web");
  EXPECT_EQ(resolve_web_path(root, "/"), (root / "index.html").string());
  EXPECT_EQ(resolve_web_path(root, "/sub/a.js"), (root / "sub" / "a.js").string());
  for (const char* bad : {"/../secret.txt", "/sub/../../secret.txt", "/sub/../index.html", "/./index.html",
                          "/.hidden", "/link.txt", "/sub", "/nope.js", "", "index.html", "/..\\secret.txt",
                          "//etc/passwd", "/sub//../../secret.txt"})
    EXPECT_EQ(resolve_web_path(root, bad), "") << bad;
  fs::remove_all(dir);
}
