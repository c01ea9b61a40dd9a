// Test-only LCM probe for the network test: records when scans and poses arrive on this host (wall clock,
// which every network namespace of one machine shares) and the last telemetry of every node.
//   fploc-test-lcm-probe --url URL --out FILE --duration S [--scan CH] [--pose CH] [--final CH] [--telemetry CH]...
//                        [--states CH]...
// --pose: the per-scan estimate (FPLOC_POSE_LATEST); --final: poses leaving the optimizer's window.
// Lines: "scan UTIME RX_US", "pose UTIME RX_US", "final UTIME RX_US",
//        "status CHANNEL NODE ROBOT HOST REPORTER in=N out=N undecodable=N port=CHANNEL:MESSAGES ..."
//        (the last one of each node, at the end), and with --states every node_status_t as it arrives
//        (written at once, for scripts reading the file during the run):
//        "state RX_US NODE REPORTER STATE RESTARTS | LAST_ERROR"
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>
#include <fploc/scan_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>

namespace {
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
volatile std::sig_atomic_t g_stop = 0;
void on_sig(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  std::string url, out;
  double duration = 60;
  std::vector<std::pair<std::string, std::string>> subs;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--url") url = argv[i + 1];
    else if (a == "--out") out = argv[i + 1];
    else if (a == "--duration") duration = std::atof(argv[i + 1]);
    else subs.push_back({a, argv[i + 1]});
  }
  std::signal(SIGINT, on_sig);
  std::signal(SIGTERM, on_sig);
  lcm::LCM lc(url);
  if (!lc.good()) return 1;
  std::ofstream f(out);
  std::map<std::string, std::string> last_status;
  struct H {
    std::ofstream* f;
    std::map<std::string, std::string>* st;
    void scan(const lcm::ReceiveBuffer*, const std::string&, const fploc::scan_t* m) {
      *f << "scan " << m->utime << " " << wall_us() << "\n";
    }
    void pose(const lcm::ReceiveBuffer*, const std::string&, const fploc::pose_t* m) {
      *f << "pose " << m->utime << " " << wall_us() << "\n";
    }
    void final_pose(const lcm::ReceiveBuffer*, const std::string&, const fploc::pose_t* m) {
      *f << "final " << m->utime << " " << wall_us() << "\n";
    }
    void status(const lcm::ReceiveBuffer*, const std::string& ch, const fploc::node_status_t* m) {
      std::string s = "status " + ch + " " + m->node + " " + (m->robot.empty() ? "-" : m->robot) + " " +
                      (m->host.empty() ? "-" : m->host) + " " + m->reporter + " in=" + std::to_string(m->messages_in) +
                      " out=" + std::to_string(m->messages_out) + " undecodable=" + std::to_string(m->undecodable);
      for (const auto& p : m->ports)
        if (!p.output) s += " port=" + p.channel + ":" + std::to_string(p.messages);
      if (m->reporter == "node") (*st)[ch + " " + m->node] = s;
    }
    void state(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) {
      *f << "state " << wall_us() << " " << m->node << " " << m->reporter << " " << m->state << " " << m->restarts
         << " | " << m->last_error << std::endl;
    }
  } h{&f, &last_status};
  for (const auto& [kind, ch] : subs) {
    if (kind == "--scan") lc.subscribe(ch, &H::scan, &h);
    else if (kind == "--pose") lc.subscribe(ch, &H::pose, &h);
    else if (kind == "--final") lc.subscribe(ch, &H::final_pose, &h);
    else if (kind == "--telemetry") lc.subscribe(ch, &H::status, &h);
    else if (kind == "--states") lc.subscribe(ch, &H::state, &h);
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (!g_stop && std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < duration)
    lc.handleTimeout(100);
  for (const auto& [k, s] : last_status) f << s << "\n";
  return 0;
}
