// The launcher's supervision policy with a fake clock and fake processes: restart policy and backoff,
// giving up, heartbeat timeout, ordered shutdown with escalation, control requests, remote nodes whose host is away.
#include "control.h"
#include "supervisor.h"
#include "udp_links.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <google/protobuf/text_format.h>
#include <map>

using namespace fploc::launch;

namespace {

struct FakeWorld : Effects {
  pid_t next_pid = 100;
  bool fail_start = false;
  std::vector<std::pair<size_t, pid_t>> starts;           // node, pid
  std::vector<std::tuple<size_t, pid_t, int>> signals;    // node, pid, signal
  std::vector<std::pair<size_t, std::string>> published;  // node, state
  std::vector<std::string> published_errors;              // the same reports' last_error
  std::vector<std::string> probes;                        // hosts probed, in order
  std::vector<std::string> logs;
  std::map<size_t, int> start_restarts;
  double now = 0;
  std::vector<double> start_times;

  pid_t start(size_t i, int restarts) override {
    if (fail_start) return -1;
    starts.push_back({i, next_pid});
    start_restarts[i] = restarts;
    start_times.push_back(now);
    return next_pid++;
  }
  void signal(size_t i, pid_t pid, int sig) override { signals.push_back({i, pid, sig}); }
  void publish(size_t i, pid_t, int, const std::string& state, const std::string& error) override {
    published.push_back({i, state});
    published_errors.push_back(error);
  }
  void probe_host(const std::string& host) override { probes.push_back(host); }
  void log(const std::string& l) override { logs.push_back(l); }
  // The signals (other than the SIGKILL to the group after an exit) sent to node i, in order.
  std::vector<int> signals_to(size_t i) const {
    std::vector<int> out;
    for (auto& [n, p, s] : signals)
      if (n == i) out.push_back(s);
    return out;
  }
};

NodePolicy node(const std::string& name, fploc::RestartPolicy::Mode mode = fploc::RestartPolicy::ON_FAILURE) {
  NodePolicy p;
  p.name = name;
  p.restart.set_mode(mode);
  p.supervised = true;
  return p;
}

NodePolicy remote(const std::string& name, const std::string& host) {
  NodePolicy p = node(name);
  p.remote = true;
  p.host = host;
  return p;
}

ExitStatus killed(int sig) { return {false, 0, sig}; }
ExitStatus code(int c) { return {true, c, 0}; }

}  // namespace

TEST(Supervisor, CrashRestartsWithExponentialBackoff) {
  FakeWorld w;
  auto p = node("a");
  p.restart.set_backoff_initial_s(0.1);
  p.restart.set_backoff_factor(2);
  p.restart.set_backoff_max_s(0.5);
  p.restart.set_max_restarts(10);
  Supervisor s({p}, {}, w);
  s.start_all(0);
  ASSERT_EQ(w.starts.size(), 1u);
  // Each crash: restart after 0.1, 0.2, 0.4, 0.5 (capped), 0.5 s.
  const double expected[] = {0.1, 0.2, 0.4, 0.5, 0.5};
  double t = 1.0;
  for (int k = 0; k < 5; ++k) {
    const pid_t pid = s.pid(0);
    ASSERT_TRUE(s.on_exit(pid, killed(SIGKILL), t));
    EXPECT_EQ(s.state(0), State::Backoff);
    s.tick(t + expected[k] - 0.01);
    EXPECT_EQ(w.starts.size(), size_t(k + 1)) << "started before its backoff";
    s.tick(t + expected[k] + 1e-9);
    ASSERT_EQ(w.starts.size(), size_t(k + 2)) << "not restarted after " << expected[k] << " s";
    EXPECT_EQ(w.start_restarts[0], k + 1);  // FPLOC_RESTARTS of the new process
    EXPECT_EQ(s.state(0), State::Running);
    t += expected[k] + 0.05;
  }
}

TEST(Supervisor, GivesUpAfterMaxRestartsInWindow) {
  FakeWorld w;
  auto p = node("a");
  p.restart.set_max_restarts(2);
  p.restart.set_window_s(10);
  p.restart.set_backoff_initial_s(0.1);
  p.restart.set_backoff_factor(1);
  Supervisor s({p}, {}, w);
  s.start_all(0);
  double t = 0.5;
  for (int k = 0; k < 2; ++k) {
    s.on_exit(s.pid(0), code(3), t);
    s.tick(t + 0.2);
    ASSERT_EQ(s.state(0), State::Running);
    t += 0.5;
  }
  s.on_exit(s.pid(0), code(3), t);
  EXPECT_EQ(s.state(0), State::Dead);
  EXPECT_EQ(w.published.back().second, "dead");
  EXPECT_EQ(s.finished(), std::optional<int>(1));
}

TEST(Supervisor, RestartWindowSlides) {
  FakeWorld w;
  auto p = node("a");
  p.restart.set_max_restarts(1);
  p.restart.set_window_s(5);
  Supervisor s({p}, {}, w);
  s.start_all(0);
  s.on_exit(s.pid(0), code(1), 1);
  s.tick(2);
  ASSERT_EQ(s.state(0), State::Running);
  // Outside the 5 s window of the first restart: allowed again.
  s.on_exit(s.pid(0), code(1), 7);
  EXPECT_EQ(s.state(0), State::Backoff);
}

TEST(Supervisor, PoliciesNeverAndAlways) {
  FakeWorld w;
  Supervisor s({node("never", fploc::RestartPolicy::NEVER), node("always", fploc::RestartPolicy::ALWAYS),
                node("onfail")},
               {}, w);
  s.start_all(0);
  s.on_exit(s.pid(0), killed(SIGSEGV), 1);
  s.on_exit(s.pid(1), code(0), 1);
  s.on_exit(s.pid(2), code(0), 1);
  EXPECT_EQ(s.state(0), State::Dead);     // failed, never restarted
  EXPECT_EQ(s.state(1), State::Backoff);  // clean exit, restarted anyway
  EXPECT_EQ(s.state(2), State::Stopped);  // clean exit, on-failure: done
  EXPECT_FALSE(s.on_exit(9999, code(0), 1)) << "not our process";
}

TEST(Supervisor, SilentNodeIsKilledAndRestarted) {
  FakeWorld w;
  auto p = node("a");
  p.heartbeat_timeout_s = 3;
  SupervisorConfig cfg;
  cfg.first_beat_grace_s = 10;
  Supervisor s({p}, cfg, w);
  s.start_all(0);
  const pid_t pid = s.pid(0);
  s.on_transport_ok();
  // Loading: no heartbeat yet, the grace period applies (10 s, not 3).
  s.tick(9.9);
  EXPECT_EQ(s.state(0), State::Running);
  for (double t = 9.95; t < 20; t += 1.0) {
    s.on_heartbeat("a", pid, t);
    s.tick(t + 0.5);
  }
  EXPECT_EQ(s.state(0), State::Running);
  // A heartbeat from another pid (an old process) does not count.
  s.on_heartbeat("a", pid + 1000, 21);
  s.tick(22.9);
  EXPECT_EQ(s.state(0), State::Running);
  s.tick(23.0);  // 3.05 s after the last heartbeat of this pid
  EXPECT_EQ(s.state(0), State::Stopping);
  ASSERT_FALSE(w.signals.empty());
  EXPECT_EQ(std::get<2>(w.signals.back()), SIGKILL);
  EXPECT_EQ(w.published.back().second, "hung");
  s.on_exit(pid, killed(SIGKILL), 23.01);
  EXPECT_EQ(s.state(0), State::Backoff);
  s.tick(23.2);
  EXPECT_EQ(s.state(0), State::Running);
  EXPECT_NE(s.pid(0), pid);
  EXPECT_EQ(s.restarts(0), 1);
}

TEST(Supervisor, NoTransportNoHeartbeatKill) {
  FakeWorld w;
  Supervisor s({node("a")}, {}, w);
  s.start_all(0);
  s.tick(100);
  EXPECT_EQ(s.state(0), State::Running) << "killed although no telemetry can arrive at all";
  EXPECT_NE(w.logs.back().find("heartbeat supervision is off"), std::string::npos);
}

TEST(Supervisor, UnsupervisedProgramIsNotWatched) {
  FakeWorld w;
  auto p = node("tcpdump");
  p.supervised = false;
  Supervisor s({p}, {}, w);
  s.start_all(0);
  s.on_transport_ok();
  s.tick(1000);
  EXPECT_EQ(s.state(0), State::Running);
}

TEST(Supervisor, ShutdownStopsProducersBeforeConsumers) {
  FakeWorld w;
  auto src = node("source"), mid = node("matcher"), sink = node("logger");
  src.outputs = {"SCAN", "FPLOC_TELEMETRY"};
  mid.inputs = {"SCAN", "FPLOC_CONTROL"};
  mid.outputs = {"POSE", "FPLOC_TELEMETRY"};
  sink.inputs = {"POSE", "FPLOC_TELEMETRY"};
  SupervisorConfig cfg;
  cfg.ignored_channels = {"FPLOC_TELEMETRY", "FPLOC_CONTROL"};
  cfg.shutdown_timeout_s = 2;
  // Listed consumer first: the order comes from the channels, not the file.
  Supervisor s({sink, mid, src}, cfg, w);
  EXPECT_EQ(s.stop_rank(2), 0);
  EXPECT_EQ(s.stop_rank(1), 1);
  EXPECT_EQ(s.stop_rank(0), 2);
  s.start_all(0);
  const pid_t p_sink = s.pid(0), p_mid = s.pid(1), p_src = s.pid(2);
  w.signals.clear();
  s.begin_shutdown(10);
  ASSERT_EQ(w.signals.size(), 1u);
  EXPECT_EQ(w.signals[0], std::make_tuple(size_t(2), p_src, SIGINT));
  // The source exits at once: the matcher is asked next, without waiting for the stage gap.
  s.on_exit(p_src, code(0), 10.05);
  s.tick(10.05);
  ASSERT_EQ(w.signals_to(1), std::vector<int>{SIGINT});
  EXPECT_TRUE(w.signals_to(0).empty());
  // The matcher takes its time: the logger is asked after the stage gap (0.25 s) anyway.
  s.tick(10.2);
  EXPECT_TRUE(w.signals_to(0).empty());
  s.tick(10.31);
  EXPECT_EQ(w.signals_to(0), std::vector<int>{SIGINT});
  s.on_exit(p_sink, code(0), 10.4);
  EXPECT_FALSE(s.finished());
  // The matcher ignores SIGINT: SIGTERM at shutdown_timeout_s, SIGKILL one second later.
  s.tick(11.99);
  EXPECT_EQ(w.signals_to(1), std::vector<int>{SIGINT});
  s.tick(12.0);
  EXPECT_EQ(w.signals_to(1), (std::vector<int>{SIGINT, SIGTERM}));
  s.tick(12.99);
  EXPECT_EQ(w.signals_to(1).size(), 2u);
  s.tick(13.0);
  EXPECT_EQ(w.signals_to(1), (std::vector<int>{SIGINT, SIGTERM, SIGKILL}));
  s.on_exit(p_mid, killed(SIGKILL), 13.01);
  // A node had to be killed: the launcher exits 1 (it exited 0, and a script could not tell).
  EXPECT_EQ(s.finished(), std::optional<int>(1));
  EXPECT_EQ(w.logs.back(), "all nodes stopped; killed: 'matcher' (exit code 1)");
  // Nothing restarts during a shutdown.
  s.tick(20);
  EXPECT_EQ(w.starts.size(), 3u);
}

// The demo's sensor side: the simulator sends OS-1 packets over UDP to the drivers (no LCM channel between
// them). Its ports are links of the stop order, so it stops before the drivers listening on them; a driver
// reading a pcap, or packets from LCM, or another port, is not linked to it.
TEST(Supervisor, SimulatedSensorStopsBeforeTheDriversOnItsPorts) {
  auto policy = [](const std::string& text, const std::string& type) {
    fploc::Node n;
    EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &n)) << text;
    NodePolicy p = node(n.name());
    add_udp_links(n, type, p);
    return p;
  };
  const auto sim = policy(R"(name: "sim" sim { imu_port: 17503 })", "sim_sensor");
  EXPECT_EQ(sim.outputs, (std::vector<std::string>{"udp:7502", "udp:17503"}));
  auto os1 = policy(R"(name: "os1" os1_driver { lidar_port: 7502 })", "os1_driver");
  EXPECT_EQ(os1.inputs, std::vector<std::string>{"udp:7502"});
  auto imu = policy(R"(name: "imu" imu_driver { source: "os1" imu_port: 17503 })", "imu_driver");
  EXPECT_EQ(imu.inputs, std::vector<std::string>{"udp:17503"});
  EXPECT_TRUE(policy(R"(name: "p" os1_driver { pcap: "x.pcap" })", "os1_driver").inputs.empty());
  EXPECT_TRUE(policy(R"(name: "l" input { port: "packets" channel: "OS1_PACKETS" } os1_driver {})", "os1_driver").inputs.empty());
  EXPECT_TRUE(policy(R"(name: "m" matcher {})", "matcher").inputs.empty());
  // The drivers' LCM output to a consumer, as in the demo.
  os1.outputs = {"OS1_SCAN"};
  imu.outputs = {"OS1_IMU"};
  auto seg = node("segmenter");
  seg.inputs = {"OS1_SCAN", "OS1_IMU"};
  auto other = policy(R"(name: "other" os1_driver { lidar_port: 9999 })", "os1_driver");
  FakeWorld w;
  Supervisor s({seg, imu, os1, sim, other}, {}, w);
  EXPECT_EQ(s.stop_rank(3), 0);  // the simulator first
  EXPECT_EQ(s.stop_rank(2), 1);  // then the drivers on its ports
  EXPECT_EQ(s.stop_rank(1), 1);
  EXPECT_EQ(s.stop_rank(0), 2);  // then their consumer
  EXPECT_EQ(s.stop_rank(4), 0);  // a driver on another port produces nothing the simulator's order sees
}

TEST(Supervisor, CrashDuringShutdownIsNotRestarted) {
  FakeWorld w;
  auto a = node("a", fploc::RestartPolicy::ALWAYS), b = node("b", fploc::RestartPolicy::ALWAYS);
  a.outputs = {"X"};
  b.inputs = {"X"};
  Supervisor s({a, b}, {}, w);
  s.start_all(0);
  s.begin_shutdown(1);
  s.on_exit(s.pid(1), killed(SIGSEGV), 1.01);  // not asked yet, crashes on its own
  s.on_exit(s.pid(0), code(0), 1.02);
  s.tick(5);
  EXPECT_EQ(w.starts.size(), 2u);
  EXPECT_EQ(s.finished(), std::optional<int>(0));
}

TEST(Supervisor, ControlRestartAndStop) {
  FakeWorld w;
  auto p = node("a");
  p.restart.set_max_restarts(1);
  Supervisor s({p}, {}, w);
  s.start_all(0);
  const pid_t pid = s.pid(0);
  s.request_restart(0, 1);
  EXPECT_EQ(w.signals_to(0), std::vector<int>{SIGINT});
  EXPECT_EQ(s.state(0), State::Stopping);
  s.on_exit(pid, code(0), 1.1);  // stopped on request: started again at once, no backoff
  EXPECT_EQ(s.state(0), State::Running);
  EXPECT_EQ(s.restarts(0), 1);
  EXPECT_EQ(w.start_restarts[0], 1);
  // The window was reset by the request: a crash now is still restarted.
  s.on_exit(s.pid(0), code(1), 2);
  EXPECT_EQ(s.state(0), State::Backoff);
  s.tick(3);
  s.request_stop(0, 4);
  s.on_exit(s.pid(0), code(0), 4.1);
  EXPECT_EQ(s.state(0), State::Stopped);
  EXPECT_EQ(s.finished(), std::optional<int>(0));
}

TEST(Supervisor, FailedStartIsRetriedWithBackoff) {
  FakeWorld w;
  w.fail_start = true;
  Supervisor s({node("a")}, {}, w);
  s.start_all(0);
  EXPECT_EQ(s.state(0), State::Backoff);
  w.fail_start = false;
  s.tick(0.2);
  EXPECT_EQ(s.state(0), State::Running);
}

// A remote node: the launcher's process is the ssh session; the host's login shell may take long
// (a slow rc file, a loaded host) before fploc-remote starts the node. The heartbeat grace counts from
// the node's start; a session that never starts it is killed after remote_start_s.
TEST(Supervisor, RemoteNodeGraceCountsFromTheNodesStartNotTheSessions) {
  FakeWorld w;
  auto p = node("r");
  p.remote = true;
  SupervisorConfig cfg;
  cfg.first_beat_grace_s = 10;
  cfg.remote_start_s = 60;
  Supervisor s({p, p}, cfg, w);
  s.start_all(0);
  s.on_transport_ok();
  const pid_t pid0 = s.pid(0);
  s.tick(25);  // node 0's shell still starting after 25 s: not a hang
  EXPECT_EQ(s.state(0), State::Running);
  s.on_remote_started(0, 25);
  s.tick(34.9);  // 9.9 s after the node started, no heartbeat yet: still the grace
  EXPECT_EQ(s.state(0), State::Running);
  s.on_heartbeat("r", pid0, 34.9);
  s.tick(37.8);
  EXPECT_EQ(s.state(0), State::Running);
  s.tick(38.0);  // silent 3.1 s after its first heartbeat: hung
  EXPECT_EQ(s.state(0), State::Stopping);
  // Node 1's session never starts the node: killed once remote_start_s has passed, with its reason.
  EXPECT_EQ(s.state(1), State::Running);
  s.tick(60.5);
  EXPECT_EQ(s.state(1), State::Stopping);
  ASSERT_FALSE(w.logs.empty());
  EXPECT_NE(w.logs.back().find("ssh session did not start the node"), std::string::npos) << w.logs.back();
}

TEST(Supervisor, ANodeDeadDuringTheRunMakesTheShutdownsExitCodeOne) {
  FakeWorld w;
  auto a = node("a"), b = node("b");
  a.restart.set_max_restarts(1);
  a.restart.set_window_s(10);
  a.restart.set_backoff_initial_s(0.1);
  Supervisor s({a, b}, {}, w);
  s.start_all(0);
  s.on_exit(s.pid(0), code(1), 0.5);
  s.tick(0.7);
  ASSERT_EQ(s.state(0), State::Running);
  s.on_exit(s.pid(0), code(1), 0.8);
  ASSERT_EQ(s.state(0), State::Dead);
  EXPECT_FALSE(s.finished());  // b still runs
  s.begin_shutdown(5);
  s.on_exit(s.pid(1), code(0), 5.1);
  EXPECT_EQ(s.finished(), std::optional<int>(1));
  EXPECT_EQ(w.logs.back(), "all nodes stopped; dead during the run: 'a' (exit code 1)");
}

TEST(Supervisor, ACleanShutdownExitsZero) {
  FakeWorld w;
  Supervisor s({node("a"), node("b")}, {}, w);
  s.start_all(0);
  s.begin_shutdown(5);
  s.tick(5.3);
  s.on_exit(s.pid(0), code(0), 5.4);
  s.on_exit(s.pid(1), code(0), 5.4);
  EXPECT_EQ(s.finished(), std::optional<int>(0));
  EXPECT_EQ(w.logs.back(), "all nodes stopped");
}

TEST(Supervisor, ANodeRevivedByAControlRestartNoLongerCountsAsDead) {
  FakeWorld w;
  auto a = node("a", fploc::RestartPolicy::NEVER);
  Supervisor s({a, node("b")}, {}, w);
  s.start_all(0);
  s.on_exit(s.pid(0), code(1), 0.5);
  ASSERT_EQ(s.state(0), State::Dead);
  s.request_restart(0, 1.0);
  ASSERT_EQ(s.state(0), State::Running);
  s.begin_shutdown(5);
  s.tick(5.3);
  s.on_exit(s.pid(0), code(0), 5.4);
  s.on_exit(s.pid(1), code(0), 5.4);
  EXPECT_EQ(s.finished(), std::optional<int>(0));
}

// ---- Remote nodes whose host is away (the user trial: a host that did not answer made its nodes fail five times
// and end dead, and nothing started them again once it was back).

const std::string kAway = "not reachable with ssh (10.0.0.2 as root): ssh: connect to host 10.0.0.2 port 22: No route to host";

// A remote node's ssh session ends with ssh's own code (255) and the host does not answer: the node waits for the
// host, spends no restart, is probed with backoff and starts again when the host answers -- outage after outage,
// more of them than the restart policy allows restarts.
TEST(Supervisor, ARemoteNodeWaitsForItsHostWithoutSpendingItsRestarts) {
  FakeWorld w;
  auto p = remote("matcher", "compute");
  p.restart.set_max_restarts(2);
  p.restart.set_window_s(600);
  p.restart.set_backoff_initial_s(0.1);
  SupervisorConfig cfg;
  cfg.host_probe_initial_s = 0.5;
  cfg.host_probe_max_s = 4;
  Supervisor s({p}, cfg, w);
  s.start_all(0);
  double t = 10;
  for (int outage = 0; outage < 4; ++outage) {
    const size_t probes_before = w.probes.size();
    ASSERT_TRUE(s.on_exit(s.pid(0), code(255), t));
    EXPECT_EQ(s.state(0), State::WaitingForHost);
    EXPECT_EQ(s.waiting_for(0), "compute");
    ASSERT_EQ(w.probes.size(), probes_before + 1) << "the host is probed at once";
    EXPECT_EQ(w.published.back().second, "waiting");
    // The probe does not get there: the node waits for the host (said in the log and in its telemetry).
    s.on_host_probe("compute", false, kAway, t + 3);
    EXPECT_EQ(s.state(0), State::WaitingForHost);
    EXPECT_NE(w.published_errors.back().find("waiting for host 'compute': " + kAway), std::string::npos)
        << w.published_errors.back();
    EXPECT_NE(w.logs.back().find("host 'compute' " + kAway + ": node 'matcher' waiting for host 'compute'"),
              std::string::npos) << w.logs.back();
    // Probes with backoff: 0.5, 1, 2, 4, 4, ... s after each failed answer (an answer takes 0.1 s here).
    double at = t + 3;
    for (double gap : {0.5, 1.0, 2.0, 4.0, 4.0, 4.0}) {
      const size_t n = w.probes.size();
      s.tick(at + gap - 0.01);
      EXPECT_EQ(w.probes.size(), n) << "probed before its backoff of " << gap << " s";
      s.tick(at + gap);
      ASSERT_EQ(w.probes.size(), n + 1) << "not probed after " << gap << " s";
      s.tick(at + gap + 0.05);
      EXPECT_EQ(w.probes.size(), n + 1) << "a second probe while one is under way";
      at += gap + 0.1;
      s.on_host_probe("compute", false, kAway, at);
    }
    EXPECT_EQ(s.state(0), State::WaitingForHost);
    EXPECT_EQ(s.restarts(0), outage) << "a restart spent while the host was away";
    // The host answers: the node starts at once, as a restart (FPLOC_RESTARTS), its budget untouched.
    const size_t starts = w.starts.size();
    s.tick(at + 4);
    s.on_host_probe("compute", true, "", at + 4.1);
    ASSERT_EQ(w.starts.size(), starts + 1);
    EXPECT_EQ(s.state(0), State::Running);
    EXPECT_EQ(s.restarts(0), outage + 1);
    EXPECT_EQ(w.start_restarts[0], outage + 1);
    EXPECT_NE(w.logs.back().find("host 'compute' answers again"), std::string::npos) << w.logs.back();
    t = at + 20;
  }
  // Its two restarts are still there for its own crashes.
  for (int k = 0; k < 2; ++k) {
    s.on_exit(s.pid(0), code(1), t);
    ASSERT_EQ(s.state(0), State::Backoff);
    s.tick(t + 1);
    ASSERT_EQ(s.state(0), State::Running);
    t += 2;
  }
  s.on_exit(s.pid(0), code(1), t);
  EXPECT_EQ(s.state(0), State::Dead);
}

// ssh's code 255 is also what a node itself may exit with (exit(-1)). When the host answers the probe at once, the
// failure is the node's own: charged to the restart policy, and a node that keeps failing ends dead as before.
TEST(Supervisor, ARemoteNodeFailingOnAReachableHostStillEndsDead) {
  FakeWorld w;
  auto p = remote("crasher", "compute");
  p.restart.set_max_restarts(3);
  p.restart.set_window_s(60);
  p.restart.set_backoff_initial_s(0.1);
  p.restart.set_backoff_factor(1);
  Supervisor s({p}, {}, w);
  s.start_all(0);
  double t = 1;
  for (int k = 0; k < 3; ++k) {
    s.on_exit(s.pid(0), code(255), t);
    ASSERT_EQ(s.state(0), State::WaitingForHost);
    s.on_host_probe("compute", true, "", t + 0.05);
    ASSERT_EQ(s.state(0), State::Backoff) << "restart " << k;
    EXPECT_NE(std::find_if(w.logs.begin(), w.logs.end(),
                           [](const std::string& l) { return l.find("failed on its own") != std::string::npos; }),
              w.logs.end());
    s.tick(t + 0.2);
    ASSERT_EQ(s.state(0), State::Running);
    t += 0.5;
  }
  s.on_exit(s.pid(0), code(255), t);
  s.on_host_probe("compute", true, "", t + 0.05);
  EXPECT_EQ(s.state(0), State::Dead);
  EXPECT_EQ(w.published.back().second, "dead");
  EXPECT_EQ(s.finished(), std::optional<int>(1));
  // A crash that is not ssh's (a signal, another code) is not a reason to ask the host.
  FakeWorld w2;
  Supervisor s2({remote("r", "compute")}, {}, w2);
  s2.start_all(0);
  s2.on_exit(s2.pid(0), killed(SIGSEGV), 1);
  EXPECT_EQ(s2.state(0), State::Backoff);
  EXPECT_TRUE(w2.probes.empty());
}

// The launch's check did not reach a host and the launch is to wait for it: the other nodes start, the host's nodes
// wait; when the host answers they start as first starts (FPLOC_RESTARTS=0). Nodes of one host share its probes.
TEST(Supervisor, AHostAwayAtTheStartLeavesItsNodesWaitingAndTheOthersRunning) {
  FakeWorld w;
  SupervisorConfig cfg;
  cfg.host_probe_initial_s = 0.5;
  Supervisor s({node("local"), remote("a", "compute"), remote("b", "compute"), remote("c", "dash")}, cfg, w);
  s.host_down_at_start("compute", kAway, 0);
  s.start_all(0);
  ASSERT_EQ(w.starts.size(), 2u);
  EXPECT_EQ(s.state(0), State::Running);
  EXPECT_EQ(s.state(1), State::WaitingForHost);
  EXPECT_EQ(s.state(2), State::WaitingForHost);
  EXPECT_EQ(s.state(3), State::Running);
  EXPECT_NE(std::find(w.logs.begin(), w.logs.end(),
                      "host 'compute' " + kAway + ": nodes 'a', 'b' waiting for host 'compute'; probing it in 0.50 s, "
                      "then with backoff (at most every 2.00 s)"),
            w.logs.end()) << w.logs.back();
  s.tick(0.49);
  EXPECT_TRUE(w.probes.empty());
  s.tick(0.5);
  ASSERT_EQ(w.probes, std::vector<std::string>{"compute"});
  s.tick(1.0);
  EXPECT_EQ(w.probes.size(), 1u) << "one probe per host, not per node";
  EXPECT_FALSE(s.finished());
  s.on_host_probe("compute", true, "", 1.2);
  ASSERT_EQ(w.starts.size(), 4u);
  EXPECT_EQ(s.state(1), State::Running);
  EXPECT_EQ(s.state(2), State::Running);
  EXPECT_EQ(w.start_restarts[1], 0);
  EXPECT_EQ(s.restarts(1), 0);
}

// The cut link is often noticed first as silence (no heartbeat): a remote node killed as hung asks its host too.
TEST(Supervisor, ASilentRemoteNodeWhoseHostIsAwayWaitsForIt) {
  FakeWorld w;
  auto p = remote("r", "compute");
  p.heartbeat_timeout_s = 3;
  Supervisor s({p}, {}, w);
  s.start_all(0);
  s.on_transport_ok();
  s.on_remote_started(0, 0.5);
  const pid_t pid = s.pid(0);
  s.on_heartbeat("r", pid, 1);
  s.tick(4.1);
  ASSERT_EQ(s.state(0), State::Stopping);  // hung: SIGKILL
  s.on_exit(pid, killed(SIGKILL), 4.2);
  EXPECT_EQ(s.state(0), State::WaitingForHost);
  ASSERT_EQ(w.probes.size(), 1u);
  EXPECT_NE(w.published_errors.back().find("checking host 'compute' after: hung, killed by signal 9"), std::string::npos)
      << w.published_errors.back();
  s.on_host_probe("compute", false, kAway, 7.2);
  EXPECT_EQ(s.state(0), State::WaitingForHost);
  s.on_host_probe("compute", true, "", 12);
  EXPECT_EQ(s.state(0), State::Running);
  EXPECT_EQ(s.restarts(0), 1);
}

// A node waiting for its host: re-reported every second, stopped by a control request (probes end), and at a
// shutdown it counts, like a dead node, for the exit code 1 (it did not run).
TEST(Supervisor, AWaitingNodeIsReportedStoppableAndMakesTheExitCodeOne) {
  FakeWorld w;
  Supervisor s({node("local"), remote("a", "compute"), remote("b", "compute")}, {}, w);
  s.host_down_at_start("compute", kAway, 0);
  s.start_all(0);
  w.published.clear();
  s.tick(1.1);
  EXPECT_NE(std::find(w.published.begin(), w.published.end(), std::make_pair(size_t(1), std::string("waiting"))),
            w.published.end());
  s.request_stop(2, 1.5);
  EXPECT_EQ(s.state(2), State::Stopped);
  EXPECT_EQ(s.waiting_for(2), "");
  s.on_host_probe("compute", false, kAway, 1.6);
  s.begin_shutdown(5);
  s.on_exit(s.pid(0), code(0), 5.1);
  EXPECT_EQ(s.finished(), std::optional<int>(1));
  EXPECT_EQ(w.logs.back(), "all nodes stopped; still waiting for their host: 'a' (exit code 1)");
  const size_t probes = w.probes.size();
  s.tick(30);
  EXPECT_EQ(w.probes.size(), probes) << "probing during the shutdown";
}

// A node whose set-up failed (exit code kSetupFailedExitCode: its options or files) would fail the same way
// on every restart: it is not restarted, that is said once, and the launch stops with exit code 1.
TEST(Supervisor, ASetupFailureIsNotRestartedAndStopsTheLaunch) {
  FakeWorld w;
  Supervisor s({node("matcher"), node("b")}, {}, w);
  s.start_all(0);
  ASSERT_EQ(w.starts.size(), 2u);
  s.on_exit(s.pid(0), code(fploc::rt::kSetupFailedExitCode), 0.3);
  EXPECT_NE(std::find(w.published.begin(), w.published.end(), std::pair<size_t, std::string>(0, "dead")),
            w.published.end());
  EXPECT_TRUE(s.shutting_down());
  for (double t = 0.4; t < 3; t += 0.1) s.tick(t);
  EXPECT_EQ(w.starts.size(), 2u) << "restarted after a set-up failure";
  EXPECT_EQ(std::count_if(w.logs.begin(), w.logs.end(),
                          [](const std::string& l) { return l.find("failed at set-up") != std::string::npos; }),
            1);
  ASSERT_FALSE(w.signals_to(1).empty()) << "the other node was not stopped";
  EXPECT_EQ(w.signals_to(1).front(), SIGINT);
  s.on_exit(s.pid(1), code(0), 3.1);
  EXPECT_EQ(s.finished(), std::optional<int>(1));
  EXPECT_EQ(w.logs.back(), "all nodes stopped; dead during the run: 'matcher' (exit code 1)");
}

// Only the first start's set-up failure stops the launch: a node that ran, crashed and then fails at set-up goes by
// its restart policy (the set-up may have failed on something the crash left behind).
TEST(Supervisor, ASetupFailureAfterARestartGoesByThePolicy) {
  FakeWorld w;
  Supervisor s({node("matcher"), node("b")}, {}, w);
  s.start_all(0);
  s.on_exit(s.pid(0), code(1), 5.0);  // a crash after running
  for (double t = 5.1; t < 8 && w.starts.size() < 3; t += 0.1) s.tick(t);
  ASSERT_EQ(w.starts.size(), 3u) << "the crashed node was not restarted";
  s.on_exit(s.pid(0), code(fploc::rt::kSetupFailedExitCode), 8.2);
  EXPECT_FALSE(s.shutting_down()) << "a restart's set-up failure stopped the launch";
  for (double t = 8.3; t < 15 && w.starts.size() < 4; t += 0.1) s.tick(t);
  EXPECT_EQ(w.starts.size(), 4u) << "not restarted by the policy";
}

// A control request for a name that is not in the graph is refused naming the graph's nodes.
TEST(Control, UnknownNodeIsRefusedListingTheNodes) {
  fploc::Graph g;
  g.add_node()->set_name("matcher");
  g.add_node()->set_name("optimizer");
  auto* off = g.add_node();
  off->set_name("old");
  off->set_disabled(true);
  fploc::node_command_t m{};
  m.node = "nosuch";
  m.action = "restart";
  const auto d = decide_control(m, nullptr, g, fploc::rt::ValidateHooks{});
  EXPECT_EQ(d.kind, ControlDecision::Reject);
  EXPECT_EQ(d.error, "no running node named 'nosuch' (nodes: matcher, optimizer)");
}
