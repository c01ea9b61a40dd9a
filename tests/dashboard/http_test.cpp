// The dashboard over HTTP, fed by fake publishers over LCM (run inside a network namespace by ctest):
// endpoints, SSE rate cap and latest-value pushes, path traversal, read-only, loopback-only default bind.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>

#include "../support/process.h"

using nlohmann::json;
using namespace std::chrono_literals;

namespace {
using fploc::test::build_dir;
using fploc::test::spawn;
using fploc::test::stop;

// One raw HTTP/1.0 request exactly as written (no client-side path normalisation).
std::string raw_request(const std::string& request_line) {
  int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(8080);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return "";
  }
  const std::string req = request_line + "\r\nHost: 127.0.0.1:8080\r\nConnection: close\r\n\r\n";
  (void)!write(fd, req.data(), req.size());
  std::string out;
  char buf[4096];
  ssize_t n;
  while ((n = read(fd, buf, sizeof buf)) > 0) out.append(buf, size_t(n));
  close(fd);
  return out;
}
int status_of(const std::string& response) {
  return response.size() > 12 ? std::atoi(response.substr(9, 3).c_str()) : 0;
}

class DashboardHttp : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string bin = build_dir() + "/bin/";
    const std::string plan = std::string(FPLOC_SOURCE_DIR) + "/tests/dashboard/room.json";
    dash_ = spawn({bin + "fploc-dashboard", "--set", "plan.file=" + plan});
    sim_ = spawn({bin + "fploc-dashboard-fake", "--name", "sim", "--sim", "--rate", "100"});
    seg_ = spawn({bin + "fploc-dashboard-fake", "--name", "segmenter"});
    httplib::Client c("127.0.0.1", 8080);
    for (int i = 0; i < 100; ++i) {
      if (auto r = c.Get("/api/info"); r && r->status == 200) break;
      std::this_thread::sleep_for(100ms);
    }
    std::this_thread::sleep_for(1500ms);  // a heartbeat from every fake, poses for a while
  }
  static void TearDownTestSuite() {
    stop(sim_);
    stop(seg_);
    stop(dash_);
  }
  static pid_t dash_, sim_, seg_;
  httplib::Client client_{"127.0.0.1", 8080};
};
pid_t DashboardHttp::dash_ = -1, DashboardHttp::sim_ = -1, DashboardHttp::seg_ = -1;

TEST_F(DashboardHttp, ServesThePageAndItsModules) {
  auto r = client_.Get("/");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_NE(r->get_header_value("Content-Type").find("text/html"), std::string::npos);
  EXPECT_NE(r->body.find("<title>"), std::string::npos);
  r = client_.Get("/app.js");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_NE(r->get_header_value("Content-Type").find("javascript"), std::string::npos);
  EXPECT_EQ(r->get_header_value("X-Content-Type-Options"), "nosniff");
}

TEST_F(DashboardHttp, PlanStateAndHistory) {
  auto r = client_.Get("/api/plan");
  ASSERT_TRUE(r);
  auto plan = json::parse(r->body);
  EXPECT_EQ(plan["elements"].size(), 6u);
  EXPECT_NEAR(plan["bounds"][2].get<double>(), 12.0, 1e-6);
  r = client_.Get("/api/state");
  ASSERT_TRUE(r);
  auto st = json::parse(r->body);
  for (const char* k : {"pose", "gt", "frame_pose", "features", "nodes"}) EXPECT_TRUE(st.contains(k)) << k;
  std::vector<std::string> names;
  for (const auto& n : st["nodes"]["nodes"]) names.push_back(n["node"]);
  EXPECT_NE(std::find(names.begin(), names.end(), "sim"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "segmenter"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "dashboard"), names.end());  // its own heartbeat
  EXPECT_GT(st["pose"]["ate_n"].get<int>(), 10);
  EXPECT_LT(st["pose"]["ate_rmse"].get<double>(), 0.1);  // the fake estimate is within 7 cm of truth
  EXPECT_GT(st["features"]["xy"].size(), 100u);
  r = client_.Get("/api/history");
  ASSERT_TRUE(r);
  auto h = json::parse(r->body);
  EXPECT_GT(h["est"].size(), 50u);
  EXPECT_GT(h["gt"].size(), 50u);
  // Gap filling: only entries after `since`.
  const int64_t since = h["est"][h["est"].size() - 5][0];
  r = client_.Get(("/api/history?since=" + std::to_string(since)).c_str());
  ASSERT_TRUE(r);
  auto tail = json::parse(r->body);
  ASSERT_GE(tail["est"].size(), 4u);
  for (const auto& e : tail["est"]) EXPECT_GT(e[0].get<int64_t>(), since);
  r = client_.Get("/api/history?since=abc");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
}

TEST_F(DashboardHttp, EventsAreRateCappedLatestValues) {
  // Poses come at 100 Hz; the stream must carry at most 20 pushes per second, each with the newest pose.
  int pose_events = 0, keepalives = 0;
  int64_t last_seq = -1, max_gap = 0;
  std::vector<double> lat_ms;  // pose stamp -> this client (no browser), same clock
  std::string buffer;
  const auto t0 = std::chrono::steady_clock::now();
  httplib::Client c("127.0.0.1", 8080);
  c.set_read_timeout(5, 0);
  c.Get("/api/events", [&](const char* data, size_t n) {
    buffer.append(data, n);
    size_t pos;
    while ((pos = buffer.find("\n\n")) != std::string::npos) {
      const std::string ev = buffer.substr(0, pos);
      buffer.erase(0, pos + 2);
      if (ev.rfind("event: pose\n", 0) == 0) {
        auto j = json::parse(ev.substr(ev.find("data: ") + 6));
        const int64_t seq = j["seq"];
        const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                                   std::chrono::system_clock::now().time_since_epoch()).count();
        lat_ms.push_back(double(now_us - j["utime"].get<int64_t>()) / 1e3);
        if (last_seq >= 0) max_gap = std::max(max_gap, seq - last_seq);
        last_seq = seq;
        ++pose_events;
      } else if (ev.rfind(":", 0) == 0) {
        ++keepalives;
      }
    }
    return std::chrono::steady_clock::now() - t0 < 3s;
  });
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "SSE: " << pose_events << " pose events in " << secs << " s (" << pose_events / secs
            << " Hz) with poses at 100 Hz; largest seq step " << max_gap << "\n";
  std::sort(lat_ms.begin(), lat_ms.end());
  if (!lat_ms.empty())
    std::cout << "SSE latency pose stamp -> HTTP client: p50 " << lat_ms[lat_ms.size() / 2] << " ms, p95 "
              << lat_ms[lat_ms.size() * 95 / 100] << " ms, max " << lat_ms.back() << " ms\n";
  EXPECT_LE(pose_events, int(20 * secs) + 2);
  EXPECT_GE(pose_events, int(12 * secs));
  EXPECT_GE(max_gap, 3);  // intermediate poses were skipped, not queued
}

TEST_F(DashboardHttp, NoFileOutsideWebIsServed) {
  for (const std::string path :
       {"/../CMakeLists.txt", "/%2e%2e/CMakeLists.txt", "/..%2fCMakeLists.txt", "/%2E%2E%2F%2E%2E%2Fetc%2Fpasswd",
        "/../../../../../../etc/passwd", "/web/../../etc/passwd", "//etc/passwd", "/.%2e/CMakeLists.txt",
        "/..%5cCMakeLists.txt", "/%00index.html", "/../nodes/dashboard/dashboard_node.cpp",
        "http://127.0.0.1:8080/../CMakeLists.txt", "/.git/config"}) {
    const std::string res = raw_request("GET " + path + " HTTP/1.0");
    const int status = status_of(res);
    EXPECT_TRUE(status == 404 || status == 400 || status == 403) << path << " -> " << res.substr(0, 40);
    EXPECT_EQ(res.find("cmake_minimum_required"), std::string::npos) << path;
    EXPECT_EQ(res.find("root:"), std::string::npos) << path;
    EXPECT_EQ(res.find("FPLOC_REGISTER_NODE"), std::string::npos) << path;
  }
  EXPECT_EQ(status_of(raw_request("GET /index.html HTTP/1.0")), 200);  // the same socket path works for a real file
}

TEST_F(DashboardHttp, ReadOnlyByDefault) {
  auto r = client_.Post("/api/command", R"({"node":"segmenter","action":"stop"})", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 403);
  r = client_.Post("/api/plan", "{}", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 405);
}

TEST_F(DashboardHttp, ListensOnLoopbackOnlyByDefault) {
  std::ifstream in("/proc/net/tcp");
  std::string line;
  bool found = false;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string sl, local, remote, state;
    ss >> sl >> local >> remote >> state;
    if (state == "0A" && local.size() > 5 && local.substr(local.size() - 4) == "1F90") {  // LISTEN on 8080
      found = true;
      EXPECT_EQ(local, "0100007F:1F90");
    }
  }
  EXPECT_TRUE(found);
}

}  // namespace

namespace {
TEST(DashboardFlags, BindAndPortFlags) {
  const std::string bin = build_dir() + "/bin/";
  pid_t d = spawn({bin + "fploc-dashboard", "--bind", "127.0.0.1", "--port", "18081"});
  httplib::Client c("127.0.0.1", 18081);
  bool up = false;
  for (int i = 0; i < 100 && !up; ++i) {
    auto r = c.Get("/api/info");
    up = r && r->status == 200 && json::parse(r->body)["port"] == 18081;
    if (!up) std::this_thread::sleep_for(100ms);
  }
  stop(d);
  EXPECT_TRUE(up);
}
}  // namespace

namespace {
// The dashboard cannot listen (its port is taken by another program): while that lasts its own telemetry says so —
// state "failing", last_error naming host:port and the reason — and another dashboard shows its row as bad; once the
// port is free it listens, and its row is ok again with last_error cleared. (Its row stayed "ok" while it logged the
// error once and retried.)
json row_of(httplib::Client& c, const std::string& node) {
  auto r = c.Get("/api/state");
  if (!r || r->status != 200) return nullptr;
  const json s = json::parse(r->body, nullptr, false);
  if (!s.is_object() || !s.contains("nodes")) return nullptr;
  for (const auto& n : s["nodes"]["nodes"])
    if (n.value("node", "") == node) return n;
  return nullptr;
}

TEST(DashboardFlags, AFailedBindIsInItsTelemetryUntilItListens) {
  const std::string bin = build_dir() + "/bin/";
  // Port 18082 taken.
  int taken = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);  // not inherited by the dashboards spawned below
  ASSERT_GE(taken, 0);
  const int one = 1;
  setsockopt(taken, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(18082);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(taken, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(taken, 4), 0);
  // The dashboard that cannot listen, as the node 'busy_dash' of a graph; another one on 18083 watches.
  char dir[] = "/tmp/fploc-dash-bind-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string graph = std::string(dir) + "/busy.pbtxt";
  std::ofstream(graph) << "name: \"busy\"\nnode { name: \"busy_dash\" executable: \"fploc-dashboard\" dashboard { port: 18082 } }\n";
  pid_t busy = spawn({bin + "fploc-dashboard", "--graph", graph, "--node", "busy_dash"});
  pid_t watch = spawn({bin + "fploc-dashboard", "--port", "18083"});
  httplib::Client c("127.0.0.1", 18083);
  json row;
  for (int i = 0; i < 100; ++i) {  // a heartbeat that says it is failing
    row = row_of(c, "busy_dash");
    if (row.is_object() && row.value("state", "") == "failing") break;
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_TRUE(row.is_object()) << "no row for busy_dash";
  EXPECT_EQ(row.value("state", ""), "failing") << row.dump();
  EXPECT_EQ(row.value("health", ""), "bad") << row.dump();
  const std::string err = row.value("last_error", "");
  EXPECT_NE(err.find("cannot listen on 127.0.0.1:18082"), std::string::npos) << err;
  EXPECT_NE(err.find("Address already in use"), std::string::npos) << err;
  EXPECT_NE(row.value("reason", "").find("127.0.0.1:18082"), std::string::npos) << row.dump();
  // The port freed: it listens, and its next heartbeats say it is running, without the error.
  close(taken);
  httplib::Client b("127.0.0.1", 18082);
  bool up = false;
  for (int i = 0; i < 100 && !up; ++i) {
    auto r = b.Get("/api/info");
    up = r && r->status == 200;
    if (!up) std::this_thread::sleep_for(100ms);
  }
  EXPECT_TRUE(up) << "busy_dash does not listen on 18082 once it is free";
  for (int i = 0; i < 50; ++i) {
    row = row_of(c, "busy_dash");
    if (row.is_object() && row.value("state", "") == "running") break;
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(row.value("state", ""), "running") << row.dump();
  EXPECT_EQ(row.value("health", ""), "ok") << row.dump();
  EXPECT_EQ(row.value("last_error", "x"), "") << row.dump();
  stop(busy);
  stop(watch);
  std::filesystem::remove_all(dir);
}
}  // namespace
