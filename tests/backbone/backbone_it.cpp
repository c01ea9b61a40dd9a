// Backbone integration tests (each case runs in its own network namespace, see CMakeLists.txt):
// launcher validation, restart after kill -9, hung node, module swap, clean shutdown, log playback with
// lcm-logger/lcm-logplayer and byte-identical `fploc replay`.
#include <fcntl.h>
#include <fploc/node_command_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../support/process.h"

namespace fs = std::filesystem;
using namespace fploc::test;

namespace {

const std::string kRoot = root();
// Graph files used only by tests live in tests/graphs (graphs/ holds the shipped ones).
std::string graph(const std::string& name) { return kRoot + "/tests/graphs/" + name; }
std::string lcm_url_of(const std::string& graph_file) {
  std::smatch m;
  const std::string text = slurp(graph_file);
  if (std::regex_search(text, m, std::regex("lcm_url:\\s*\"([^\"]*)\""))) return m[1];
  return "";
}

// Listens to FPLOC_TELEMETRY in the test.
struct Telemetry {
  lcm::LCM lcm;
  std::vector<fploc::node_status_t> seen;
  explicit Telemetry(const std::string& url) : lcm(url) {
    lcm.subscribe("FPLOC_TELEMETRY", &Telemetry::on, this);
  }
  void on(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) { seen.push_back(*m); }
  // Pumps until pred(status) holds for a new message; returns it (or nullptr after timeout).
  const fploc::node_status_t* until(double timeout_s, const std::function<bool(const fploc::node_status_t&)>& pred) {
    const double t0 = now_s();
    size_t i = seen.size();
    while (now_s() - t0 < timeout_s) {
      lcm.handleTimeout(20);
      for (; i < seen.size(); ++i)
        if (pred(seen[i])) return &seen[i];
    }
    return nullptr;
  }
};

class Backbone : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = (fs::temp_directory_path() / ("fploc-bb-" + std::string(info->name()) + "-" + std::to_string(getpid())))
               .string();
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
    else std::cerr << "test files kept in " << dir_ << "\n";
  }
  std::string dir_;
};

int count_lines(const std::string& p) {
  std::ifstream in(p);
  int n = 0;
  for (std::string l; std::getline(in, l);) n += !l.empty();
  return n;
}

}  // namespace

TEST_F(Backbone, ShippedGraphsPassCheck) {
  int checked = 0;
  for (const auto& e : fs::directory_iterator(kRoot + "/graphs")) {
    if (e.path().extension() != ".pbtxt" || e.path().filename() == "test-bad.pbtxt") continue;
    // --skip-hosts: graphs/multihost.pbtxt names hosts that do not exist here (tests/multihost reaches real ones).
    const int rc = run({bin("fploc-launch"), "--check", "--skip-hosts", e.path().string()}, dir_, "check");
    EXPECT_EQ(rc, 0) << e.path() << ":\n" << slurp(dir_ + "/check.stderr");
    ++checked;
  }
  EXPECT_GE(checked, 3);
}

TEST_F(Backbone, BadGraphListsThreeErrorsWithLines) {
  const std::string g = graph("test-bad.pbtxt");
  const int rc = run({bin("fploc-launch"), "--check", g}, dir_, "check");
  EXPECT_NE(rc, 0);
  const std::string err = slurp(dir_ + "/check.stderr");
  // Expected lines, found in the file itself: the misspelt field, the mismatched input, the missing exe.
  std::map<std::string, int> want;
  {
    std::ifstream in(g);
    int n = 0;
    for (std::string l; std::getline(in, l);) {
      ++n;
      for (const char* key : {"fille:", "FPLOC_TELEMETRY", "fploc-no-such-node"})
        if (l.find(key) != std::string::npos && l.find('#') == std::string::npos) want[key] = n;
    }
  }
  ASSERT_EQ(want.size(), 3u);
  std::vector<std::string> lines;
  std::stringstream ss(err);
  for (std::string l; std::getline(ss, l);)
    if (l.rfind(g + ":", 0) == 0 && std::regex_search(l, std::regex("^[^:]+:[0-9]+: "))) lines.push_back(l);
  ASSERT_EQ(lines.size(), 3u) << err;
  EXPECT_NE(lines[0].find(":" + std::to_string(want["fille:"]) + ": "), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("fille"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find(":" + std::to_string(want["FPLOC_TELEMETRY"]) + ": "), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("fploc.node_status_t"), std::string::npos) << lines[1];
  EXPECT_NE(lines[2].find(":" + std::to_string(want["fploc-no-such-node"]) + ": "), std::string::npos) << lines[2];
  EXPECT_NE(lines[2].find("not found"), std::string::npos) << lines[2];
}

TEST_F(Backbone, KilledNodeIsBackWithinOneSecondAndSigintStopsAll) {
  const std::string g = graph("test-launch.pbtxt");
  Telemetry tel(lcm_url_of(g));
  Proc launcher = Proc::spawn({bin("fploc-launch"), g}, dir_, "launch");
  const auto* first = tel.until(10, [](const auto& s) { return s.node == "source" && s.reporter == "node"; });
  ASSERT_TRUE(first) << slurp(launcher.err_file);
  const int old_pid = first->pid;
  ASSERT_EQ(first->restarts, 0);
  const double t_kill = now_s();
  ASSERT_EQ(kill(old_pid, SIGKILL), 0);
  const auto* back = tel.until(5, [&](const auto& s) {
    return s.node == "source" && s.reporter == "node" && s.pid != old_pid && s.state == "running";
  });
  const double dt = now_s() - t_kill;
  ASSERT_TRUE(back) << slurp(launcher.err_file);
  EXPECT_LT(dt, 1.0) << "restart took " << dt << " s";
  EXPECT_EQ(back->restarts, 1);  // the node's own heartbeat counts the restart (FPLOC_RESTARTS)
  bool launcher_reported = false;
  for (const auto& s : tel.seen)
    launcher_reported |= s.node == "source" && s.reporter == "launcher" && s.state == "restarting" && s.restarts == 1;
  EXPECT_TRUE(launcher_reported);
  std::cerr << "restart latency (kill -9 -> first heartbeat of the new process): " << int(dt * 1000) << " ms\n";

  // Every process of the graph, then SIGINT to the launcher.
  std::set<int> pids;
  tel.until(1.5, [&](const auto& s) { return false; });
  for (const auto& s : tel.seen)
    if (s.reporter == "node" && s.pid != old_pid) pids.insert(s.pid);
  ASSERT_GE(pids.size(), 2u);
  // Per-input latency in the heartbeat: the logger's pose port received messages and timed them.
  bool port_latency = false;
  for (const auto& s : tel.seen)
    for (const auto& p : s.ports)
      if (s.node == "logger" && p.port == "pose" && !p.output && p.rate_hz > 0)
        port_latency |= p.latency_p99_ms > 0 && p.latency_p99_ms >= p.latency_p50_ms;
  EXPECT_TRUE(port_latency) << "no logger heartbeat with the pose port's latency";
  const double t_int = now_s();
  kill(launcher.pid, SIGINT);
  const int st = launcher.wait(10);
  ASSERT_GE(st, 0) << "launcher did not exit";
  EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << slurp(launcher.err_file);
  for (int p : pids) EXPECT_FALSE(pid_alive(p)) << "pid " << p << " outlived the launcher";
  const double ds = now_s() - t_int;
  EXPECT_LT(ds, 5.0);
  std::cerr << "shutdown (SIGINT -> launcher and all nodes gone): " << int(ds * 1000) << " ms\n";
  EXPECT_GT(count_lines(dir_ + "/test-launch-poses.tum"), 5);
}

TEST_F(Backbone, LauncherKilledTakesNodesWithIt) {
  const std::string g = graph("test-launch.pbtxt");
  Telemetry tel(lcm_url_of(g));
  Proc launcher = Proc::spawn({bin("fploc-launch"), g}, dir_, "launch");
  std::set<int> pids;
  tel.until(10, [&](const auto& s) {
    if (s.reporter == "node") pids.insert(s.pid);
    return pids.size() >= 2;
  });
  ASSERT_EQ(pids.size(), 2u) << slurp(launcher.err_file);
  kill(launcher.pid, SIGKILL);  // PR_SET_PDEATHSIG
  launcher.wait(5);
  const double t0 = now_s();
  bool any = true;
  while (any && now_s() - t0 < 3) {
    any = false;
    for (int p : pids) any |= pid_alive(p);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_FALSE(any) << "a node outlived a SIGKILLed launcher";
}

TEST_F(Backbone, HungNodeIsKilledAndRestarted) {
  const std::string g = graph("test-launch.pbtxt");
  const std::string url = lcm_url_of(g);
  Telemetry tel(url);
  Proc launcher = Proc::spawn({bin("fploc-launch"), g}, dir_, "launch");
  const auto* first = tel.until(10, [](const auto& s) { return s.node == "source" && s.reporter == "node"; });
  ASSERT_TRUE(first) << slurp(launcher.err_file);
  const int old_pid = first->pid;
  fploc::node_command_t c{};
  c.node = "source";
  c.action = "test-hang";
  c.num_set = 0;
  tel.lcm.publish("FPLOC_CONTROL", &c);
  const double t0 = now_s();
  const auto* hung = tel.until(8, [](const auto& s) { return s.node == "source" && s.state == "hung"; });
  ASSERT_TRUE(hung) << slurp(launcher.err_file);
  EXPECT_EQ(hung->reporter, "launcher");
  const auto* back = tel.until(5, [&](const auto& s) {
    return s.node == "source" && s.reporter == "node" && s.pid != old_pid && s.state == "running";
  });
  ASSERT_TRUE(back) << slurp(launcher.err_file);
  EXPECT_EQ(back->restarts, 1);
  std::cerr << "hang -> restarted: " << int((now_s() - t0) * 1000) << " ms (heartbeat timeout 2 s)\n";
  EXPECT_NE(slurp(launcher.err_file).find("hung"), std::string::npos);
  kill(launcher.pid, SIGINT);
  EXPECT_GE(launcher.wait(10), 0);
}

TEST_F(Backbone, ModuleSwapRestartsOnlyThatNode) {
  const std::string g = graph("test-launch.pbtxt");
  Telemetry tel(lcm_url_of(g));
  Proc launcher = Proc::spawn({bin("fploc-launch"), g}, dir_, "launch");
  std::map<std::string, int> pid;
  tel.until(10, [&](const auto& s) {
    if (s.reporter == "node") pid[s.node] = s.pid;
    return pid.size() >= 2;
  });
  ASSERT_EQ(pid.size(), 2u) << slurp(launcher.err_file);
  const std::string swapped = dir_ + "/swapped.tum";
  EXPECT_EQ(run({bin("fploc-node"), "restart", "logger", "--graph", g, "--set", "file=" + swapped}, dir_, "node", 20),
            0)
      << slurp(dir_ + "/node.stderr");
  // A bad override is rejected by the launcher, naming the field; the node keeps running.
  EXPECT_EQ(run({bin("fploc-node"), "restart", "logger", "--graph", g, "--set", "fiel=x"}, dir_, "node2", 20), 1);
  EXPECT_NE(slurp(dir_ + "/node2.stderr").find("fiel"), std::string::npos);
  tel.seen.clear();
  tel.until(2.5, [](const auto&) { return false; });
  std::map<std::string, int> now;
  for (const auto& s : tel.seen)
    if (s.reporter == "node") now[s.node] = s.pid;
  EXPECT_EQ(now["source"], pid["source"]) << "the source must keep running";
  EXPECT_NE(now["logger"], pid["logger"]);
  EXPECT_GT(count_lines(swapped), 10);
  kill(launcher.pid, SIGINT);
  EXPECT_GE(launcher.wait(10), 0);
}

TEST_F(Backbone, LoggedRunDrivesReplayGraphLiveAndOffline) {
  // 1. Record ~2 s of the test graph's traffic with lcm-logger.
  const std::string gl = graph("test-launch.pbtxt"), gr = graph("test-replay.pbtxt");
  const std::string log = dir_ + "/run.lcm";
  {
    Proc logger = Proc::spawn({"/usr/bin/lcm-logger", "--lcm-url=" + lcm_url_of(gl), "-f", log}, dir_, "logger");
    EXPECT_EQ(run({bin("fploc-launch"), gl, "--duration", "2.5"}, dir_, "launch", 20), 0)
        << slurp(dir_ + "/launch.stderr");
    kill(logger.pid, SIGINT);
    logger.wait(5);
  }
  int logged = 0;
  {
    lcm::LogFile lf(log, "r");
    ASSERT_TRUE(lf.good());
    while (const auto* ev = lf.readNextEvent()) logged += ev->channel == "FPLOC_POSE";
  }
  ASSERT_GT(logged, 20);

  // 2. Live: the replay graph under the launcher, the log played back with lcm-logplayer.
  const std::string url = lcm_url_of(gr);
  Telemetry tel(url);
  Proc launcher = Proc::spawn({bin("fploc-launch"), gr}, dir_, "launch-replay");
  ASSERT_TRUE(tel.until(10, [](const auto& s) { return s.node == "pose_logger" && s.reporter == "node"; }))
      << slurp(launcher.err_file);
  EXPECT_EQ(run({"/usr/bin/lcm-logplayer", "--lcm-url=" + url, "-s", "4", log}, dir_, "player", 30), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(launcher.pid, SIGINT);
  EXPECT_GE(launcher.wait(10), 0);
  const std::string live = slurp(dir_ + "/replay-poses.tum");
  const int live_lines = count_lines(dir_ + "/replay-poses.tum");
  EXPECT_GE(live_lines, logged * 9 / 10) << "live playback lost poses";

  // 3. Offline: fploc replay twice, byte-identical, one line per logged pose; live lines all match.
  for (const char* out : {"a.tum", "b.tum"})
    ASSERT_EQ(run({bin("fploc-replay"), "--graph", gr, "--log", log, "--out", dir_ + "/" + out, "--json"}, dir_,
                  std::string("replay-") + out),
              0)
        << slurp(dir_ + "/replay-" + out + ".stderr");
  const std::string a = slurp(dir_ + "/a.tum"), b = slurp(dir_ + "/b.tum");
  EXPECT_EQ(a, b);
  EXPECT_EQ(count_lines(dir_ + "/a.tum"), logged);
  std::stringstream ls(live);
  for (std::string l; std::getline(ls, l);) EXPECT_NE(a.find(l + "\n"), std::string::npos) << l;
  const std::string js = slurp(dir_ + "/replay-a.tum.stdout");
  EXPECT_NE(js.find("\"real_time_factor\""), std::string::npos) << js;
  std::cerr << "replay: " << js;
}
