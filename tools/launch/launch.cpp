// fploc launch: validates a graph (every error as file:line), then runs and supervises its nodes.
//   fploc launch GRAPH [--check] [--skip-hosts] [--wait-for-hosts] [--duration S] [--lcm-url URL]
//                [--set NODE.field=value ...]
// Three parts: the process table (process_table.h: each node its own process group with
// PR_SET_PDEATHSIG=SIGKILL, started as EXE --graph GRAPH --node NAME [--set k=v ...] [args...] with
// FPLOC_RESTARTS=<restarts so far>), the supervisor (supervisor.h: restart policy with backoff, heartbeat
// timeout on FPLOC_TELEMETRY, ordered shutdown SIGINT -> SIGTERM -> SIGKILL; pure, fake-clock tested) and
// the control channel (control.h: node_command_t on FPLOC_CONTROL from `fploc node restart`). This file is
// the event loop joining them. Events go to stderr and, as node_status_t with reporter "launcher", to
// FPLOC_TELEMETRY.
#include <fcntl.h>
#include <fploc/node_command_t.hpp>
#include <fploc/node_status_t.hpp>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fploc/runtime/bus.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/restart.h"
#include "fploc/runtime/robot.h"
#include "fploc/runtime/subprocess.h"
#include "fploc/runtime/validate.h"
#include "check_files.h"
#include "control.h"
#include "hosts.h"
#include "process_table.h"
#include "supervisor.h"
#include "udp_links.h"

using namespace fploc::rt;
using namespace fploc::launch;

namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double g_t0 = now_s();
void log_line(const std::string& msg) {
  char ts[32];
  std::snprintf(ts, sizeof ts, "%8.3f", now_s() - g_t0);
  std::cerr << "[launch " << ts << "] " << msg << std::endl;
}

int g_sig_pipe[2] = {-1, -1};
void on_signal(int sig) {
  const char c = char(sig);
  [[maybe_unused]] auto r = ::write(g_sig_pipe[1], &c, 1);
}

double policy_or(double v, double d) { return v > 0 ? v : d; }

// The graph's hosts as seen from this checkout (build/bin -> the fploc root two levels up).
std::map<std::string, std::shared_ptr<const HostPlan>> host_plans(const fploc::Graph& g, const std::string& bin_dir,
                                                                   bool multiplex = false) {
  std::map<std::string, std::shared_ptr<const HostPlan>> out;
  const auto root = std::filesystem::path(bin_dir).parent_path().parent_path().string();
  for (const auto& h : g.host()) {
    auto p = std::make_shared<HostPlan>();
    p->spec = h;
    p->local_root = root;
    p->local_bin = bin_dir;
    if (multiplex) p->control_path = "/tmp/fploc-ssh-" + std::to_string(::getpid()) + "-" + h.name();
    out[h.name()] = p;
  }
  return out;
}

// The event loop: LCM (telemetry, control), signals, the process table and the supervisor.
class Launcher : public Effects {
 public:
  // `sets`: the command line's NODE.field=value overrides (already checked against the graph).
  // `hosts_down`: hosts the launch's check did not reach (with --wait-for-hosts), and what it said.
  Launcher(LoadedGraph g, const std::vector<ResolvedNode>& resolved, std::string url, std::string bin_dir,
           const std::vector<std::string>& sets, std::vector<std::pair<std::string, std::string>> hosts_down)
      : g_(std::move(g)), robot_(robot_of(&g_.graph)), telemetry_(robot_channel(robot_, kTelemetryChannel)),
        hooks_(default_hooks(bin_dir)), bus_(url), hosts_(host_plans(g_.graph, bin_dir, true)),
        table_(entries(g_, resolved, sets, hosts_), std::filesystem::absolute(g_.path).string()),
        sup_(policies(g_, resolved), config(g_), *this), hosts_down_(std::move(hosts_down)) {
    bus_.lcm().subscribe(telemetry_, &Launcher::on_telemetry, this);
    bus_.lcm().subscribe(robot_channel(robot_, control_channel(g_.graph)), &Launcher::on_control, this);
  }

  int run(double duration) {
    // Nodes of this graph already on the bus (a second launch of the graph in the same network, or nodes a killed
    // launcher left running): their messages would mix with ours and `fploc node` commands would reach both. The
    // nodes beat once a second; listen that long before starting anything.
    for (const double t0 = now_s(); now_s() - t0 < 1.2 && foreign_.empty();) {
      pollfd p[2] = {{bus_.lcm().getFileno(), POLLIN, 0}, {g_sig_pipe[0], POLLIN, 0}};
      ::poll(p, 2, 50);
      if (p[0].revents & POLLIN) bus_.lcm().handleTimeout(0);
      if (p[1].revents & POLLIN)
        if (const auto sigs = read_signals(); !sigs.empty()) {  // Ctrl-C before anything started: nothing to stop
          log(std::string("received ") + strsignal(sigs[0]) + " before any node started: exiting");
          return 0;
        }
    }
    if (!foreign_.empty()) {
      log("refusing to start: a node named " + foreign_ + " already runs on " + bus_.url() +
          " (another launch of this graph, or its nodes left running?); stop it, or give this one another --lcm-url");
      return 1;
    }
    listening_only_ = false;
    const double t_start = now_s();
    for (size_t i = 0; i < table_.size(); ++i)
      if (table_.remote(i)) masters_[table_[i].host->spec.name()];
    for (const auto& [h, why] : hosts_down_) {
      sup_.host_down_at_start(h, why, now_s());
      masters_[h].quiet = true;  // its master fails until the host is back: said once, by the supervisor
    }
    tend_masters(false);
    // Give the master connections a moment, so that the nodes' sessions share them from the start.
    for (double t0 = now_s(); now_s() - t0 < 3.0;) {
      bool all = true;
      for (const auto& [h, m] : masters_)
        all = all && (m.quiet || std::filesystem::exists(hosts_.at(h)->control_path));
      if (all) break;
      ::usleep(20000);
    }
    sup_.start_all(now_s());
    log("graph '" + g_.graph.name() + "' running: " + std::to_string(table_.size()) + " nodes on " + bus_.url() +
        (robot_.empty() ? "" : " for robot '" + robot_ + "'") + (duration > 0 ? ", for " + fmt2(duration) + " s" : "") +
        "; control on " + robot_channel(robot_, control_channel(g_.graph)));
    const int lcm_fd = bus_.lcm().getFileno();
    double next_alive = 0;
    for (;;) {
      std::vector<pollfd> p{{lcm_fd, POLLIN, 0}, {g_sig_pipe[0], POLLIN, 0}};
      std::vector<size_t> remote_of;
      for (size_t i = 0; i < table_.size(); ++i)
        if (table_.remote(i) && table_.io(i).out >= 0) {
          p.push_back({table_.io(i).out, POLLIN, 0});
          remote_of.push_back(i);
        }
      ::poll(p.data(), nfds_t(p.size()), 20);
      if (p[0].revents & POLLIN) bus_.lcm().handleTimeout(0);
      for (size_t k = 2; k < p.size(); ++k)
        if (p[k].revents & (POLLIN | POLLHUP | POLLERR)) drain_output(remote_of[k - 2]);
      if (now_s() >= next_alive) {  // the remote watchdogs' keep-alive
        next_alive = now_s() + 0.5;
        for (size_t i = 0; i < table_.size(); ++i)
          if (table_.remote(i)) table_.send(i, '.');
      }
      if (p[1].revents & POLLIN) {
        for (const int sig : read_signals()) {
          if (!sup_.shutting_down()) {
            log(std::string("received ") + strsignal(sig) + ": stopping every node");
            sup_.begin_shutdown(now_s());
            first_signal_s_ = now_s();
          } else if (first_signal_s_ >= 0 && now_s() - first_signal_s_ < kSameStopS) {
            // The same stop delivered twice, to the launcher and to its process group (GNU timeout, systemd's
            // control-group stop): no second signal. It killed every node at once, which lost their last output.
          } else {
            log("second signal: killing every node now");
            sup_.kill_all();
          }
        }
      }
      if (!sup_.shutting_down() && duration > 0 && now_s() - t_start >= duration) {
        log("duration of " + fmt2(duration) + " s reached: stopping every node");
        sup_.begin_shutdown(now_s());
      }
      ExitStatus st;
      while (const pid_t pid = ProcessTable::reap_one(st)) {
        if (probe_ended(pid, st)) continue;
        for (auto& [h, m] : masters_)
          if (m.pid == pid) {
            m.pid = -1;
            m.next_try = now_s() + 1.0;
            // Said once per outage: while the host is away every attempt fails.
            if (!sup_.shutting_down() && !m.quiet)
              log("ssh master connection to host '" + h + "' (" + hosts_.at(h)->spec.address() + ") ended (" + st.str() +
                  "); reconnecting every second");
            m.quiet = true;
          }
        for (size_t i = 0; i < table_.size(); ++i)
          if (sup_.pid(i) == pid && table_.remote(i)) {
            drain_output(i);
            table_.close_io(i);
            if (st.exited && st.code == 255)
              log("node '" + table_[i].name + "' on host '" + table_[i].host->spec.name() + "' (" +
                  table_[i].host->spec.address() + "): ssh connection lost or refused (ssh exit 255)");
          }
        sup_.on_exit(pid, st, now_s());
      }
      time_out_probes();
      deliver_probes();
      sup_.tick(now_s());
      deliver_probes();
      tend_masters(sup_.shutting_down());
      if (auto rc = sup_.finished()) {
        for (auto& [h, m] : masters_)
          if (m.pid > 0) ProcessTable::signal_group(m.pid, SIGTERM);
        for (auto& [h, m] : masters_) std::filesystem::remove(hosts_.at(h)->control_path);
        for (auto& [pid, p] : probes_) ProcessTable::signal_group(pid, SIGKILL);
        return *rc;
      }
    }
  }

  // ---- Effects
  pid_t start(size_t i, int restarts) override {
    std::string err;
    const pid_t pid = table_.spawn(i, restarts, err);
    const auto& e = table_[i];
    if (pid < 0) {
      log("node '" + e.name + "': " + err);
      return -1;
    }
    log("node '" + e.name + "' started: " + (e.host ? "on host '" + e.host->spec.name() + "' (" + e.host->spec.address() + ") through ssh, local " : "") +
        "pid " + std::to_string(pid) + ", " + e.exe_name +
        (e.sets.empty() ? "" : " (overrides: " + join(e.sets) + ")") +
        (restarts ? ", restart " + std::to_string(restarts) : ""));
    return pid;
  }
  void signal(size_t i, pid_t pid, int sig) override {
    if (!table_.remote(i)) return ProcessTable::signal_group(pid, sig);
    // A remote node: its fploc-remote relays the signal; SIGKILL also ends the ssh session (whose end
    // makes fploc-remote kill the node, should the 'K' not arrive).
    table_.send(i, sig == SIGINT ? 'I' : sig == SIGTERM ? 'T' : 'K');
    if (sig == SIGKILL) ProcessTable::signal_group(pid, SIGKILL);
  }
  void publish(size_t i, pid_t pid, int restarts, const std::string& state, const std::string& error) override {
    fploc::node_status_t s{};
    s.utime = wall_utime();
    s.node = table_[i].name;
    s.executable = table_[i].exe_name;
    s.pid = pid;
    s.state = state;
    s.reporter = "launcher";
    s.restarts = restarts;
    s.last_error = error;
    s.num_ports = 0;
    s.robot = robot_;
    s.host = host_;
    bus_.lcm().publish(telemetry_, &s);
  }
  void log(const std::string& line) override { log_line(line); }
  // A fresh ssh connection running `true` there, in the background; its end is reaped by the event loop
  // (probe_ended) and its answer handed to the supervisor outside the supervisor's own calls.
  void probe_host(const std::string& host) override {
    const auto& plan = *hosts_.at(host);
    int out[2];
    if (::pipe2(out, O_CLOEXEC) != 0) {
      answers_.push_back({host, false, std::string("cannot probe: pipe failed: ") + strerror(errno)});
      return;
    }
    fploc::rt::SpawnOptions o;
    o.search_path = true;
    o.stdin_fd = fploc::rt::SpawnOptions::kDevNull;
    o.stdout_fd = o.stderr_fd = out[1];
    o.close_other_fds = true;
    o.who = "fploc launch";
    std::string error;
    const pid_t pid = fploc::rt::spawn_supervised(plan.probe_argv("true"), o, error);
    ::close(out[1]);
    if (pid < 0) {
      ::close(out[0]);
      answers_.push_back({host, false, "cannot probe: " + error});
      return;
    }
    ::fcntl(out[0], F_SETFL, O_NONBLOCK);
    probes_[pid] = Probe{host, out[0], now_s(), ""};
  }

 private:
  // Host probes under way (pid -> host, its output) and answers not yet given to the supervisor.
  struct Probe {
    std::string host;
    int fd = -1;
    double started = 0;
    std::string output;
  };
  struct Answer {
    std::string host;
    bool reachable = false;
    std::string why;
  };
  std::map<pid_t, Probe> probes_;
  std::vector<Answer> answers_;
  static constexpr double kProbeTimeout = 10.0;  // ssh's ConnectTimeout (3 s) ends it first, normally
  static void read_all(int fd, std::string& into) {
    char buf[4096];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) into.append(buf, size_t(n));
  }
  bool probe_ended(pid_t pid, const ExitStatus& st) {
    const auto it = probes_.find(pid);
    if (it == probes_.end()) return false;
    auto& p = it->second;
    read_all(p.fd, p.output);
    ::close(p.fd);
    const bool ok = st.exited && st.code == 0;
    const bool timed_out = !st.exited && now_s() - p.started >= kProbeTimeout;
    answers_.push_back({p.host, ok, ok ? "" : hosts_.at(p.host)->unreachable(timed_out ? -1 : st.exited ? st.code : 255, p.output)});
    probes_.erase(it);
    return true;
  }
  void time_out_probes() {
    for (auto& [pid, p] : probes_) {
      read_all(p.fd, p.output);
      if (now_s() - p.started >= kProbeTimeout) ProcessTable::signal_group(pid, SIGKILL);
    }
  }
  void deliver_probes() {
    auto answers = std::move(answers_);
    answers_.clear();
    for (const auto& a : answers) {
      sup_.on_host_probe(a.host, a.reachable, a.why, now_s());
    }
  }

  // The signals the handler wrote to the pipe since the last call, SIGCHLD left out (children are reaped anyway).
  static std::vector<int> read_signals() {
    char buf[16];
    const ssize_t n = ::read(g_sig_pipe[0], buf, sizeof buf);
    std::vector<int> out;
    for (ssize_t k = 0; k < n; ++k)
      if (buf[k] != SIGCHLD) out.push_back(buf[k]);
    return out;
  }
  // A signal within this long of the one that began the shutdown is the same stop (see run()); a later one kills.
  static constexpr double kSameStopS = 0.5;
  double first_signal_s_ = -1;  // when a signal began the shutdown (-1: none did)
  bool listening_only_ = true;  // run() has not started the nodes yet
  std::string foreign_;          // a node of this graph seen running elsewhere before that
  // One `ssh -M -N` per host in use, restarted a second after it ends (link cut, host reboot).
  void tend_masters(bool stopping) {
    if (stopping) return;
    for (auto& [h, m] : masters_) {
      if (m.quiet && m.pid > 0 && std::filesystem::exists(hosts_.at(h)->control_path)) m.quiet = false;  // up again
      if (m.pid > 0 || now_s() < m.next_try) continue;
      fploc::rt::SpawnOptions o;
      o.search_path = true;
      o.stdin_fd = fploc::rt::SpawnOptions::kDevNull;
      o.who = "fploc launch";
      // While its host is away, the attempts' "Connection timed out" every few seconds says nothing new.
      const int devnull = m.quiet ? ::open("/dev/null", O_WRONLY | O_CLOEXEC) : -1;
      o.stderr_fd = devnull;
      std::string error;
      const pid_t pid = fploc::rt::spawn_supervised(hosts_.at(h)->master_argv(), o, error);
      if (devnull >= 0) ::close(devnull);
      if (pid < 0) log_line("ssh master for host " + h + ": " + error);
      m.pid = pid;
      m.next_try = now_s() + 1.0;
    }
  }

  // A remote node's output, line by line, prefixed with its name and host.
  void drain_output(size_t i) {
    bool eof = false;
    for (const auto& l : table_.read_lines(i, eof))
      std::cerr << "[" << table_[i].name << "@" << table_[i].host->spec.name() << "] " << l << "\n";
    std::cerr.flush();
    if (table_.io(i).remote_pid > 0) sup_.on_remote_started(i, now_s());
    if (eof && table_.io(i).out >= 0) {
      ::close(table_.io(i).out);
      table_.io(i).out = -1;
    }
  }

  static std::string control_channel(const fploc::Graph& g) {
    return g.control_channel().empty() ? kControlChannel : g.control_channel();
  }
  static std::vector<ProcessEntry> entries(const LoadedGraph& g, const std::vector<ResolvedNode>& resolved,
                                           const std::vector<std::string>& sets,
                                           const std::map<std::string, std::shared_ptr<const HostPlan>>& hosts) {
    std::vector<ProcessEntry> out;
    for (const auto& rn : resolved) {
      const auto& n = g.graph.node(rn.index);
      if (n.disabled()) continue;
      ProcessEntry e;
      e.name = n.name();
      e.exe_name = n.executable();
      e.exe_path = rn.executable;
      e.fploc_node = rn.desc.describable;
      e.options_field = rn.desc.spec.options_field;
      e.spec = rn.desc.spec;
      e.args.assign(n.args().begin(), n.args().end());
      if (!n.host().empty()) e.host = hosts.at(n.host());
      for (const auto& s : sets)
        if (s.rfind(e.name + ".", 0) == 0) e.sets.push_back(s.substr(e.name.size() + 1));
      out.push_back(std::move(e));
    }
    return out;
  }
  static std::vector<NodePolicy> policies(const LoadedGraph& g, const std::vector<ResolvedNode>& resolved) {
    auto channel_of = [](const fploc::Node& n, const PortSpec& s) {
      for (const auto& p : s.output ? n.output() : n.input())
        if (p.port() == s.name) return p.channel();
      return s.default_channel;
    };
    std::vector<NodePolicy> out;
    for (const auto& rn : resolved) {
      const auto& n = g.graph.node(rn.index);
      if (n.disabled()) continue;
      NodePolicy p;
      p.name = n.name();
      p.restart = n.restart();
      p.heartbeat_timeout_s = policy_or(n.heartbeat_timeout_s(), 3.0);
      p.supervised = rn.desc.describable;
      p.remote = !n.host().empty();
      p.host = n.host();
      for (const auto& s : rn.desc.spec.ports) (s.output ? p.outputs : p.inputs).push_back(channel_of(n, s));
      add_udp_links(n, rn.desc.spec.type, p);
      out.push_back(std::move(p));
    }
    return out;
  }
  static SupervisorConfig config(const LoadedGraph& g) {
    SupervisorConfig c;
    c.shutdown_timeout_s = policy_or(g.graph.shutdown_timeout_s(), 2.0);
    c.ignored_channels = {kTelemetryChannel, control_channel(g.graph)};
    return c;
  }
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : " ") + x;
    return s;
  }

  void on_telemetry(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) {
    if (listening_only_) {  // before our own nodes start: any report of one of them comes from elsewhere
      if (foreign_.empty() && sup_.find(m->node) && m->state != "stopped" && m->state != "dead")
        foreign_ = "'" + m->node + "' (pid " + std::to_string(m->pid) + (m->host.empty() ? "" : " on " + m->host) + ")";
      return;
    }
    sup_.on_transport_ok();  // our own "starting" reports come back too when the LCM URL works here
    if (m->reporter == "launcher") return;
    // A remote node reports its pid on its host; the supervisor knows the local ssh process.
    if (auto i = sup_.find(m->node); i && table_.remote(*i)) {
      const pid_t rp = table_.io(*i).remote_pid;
      if (rp > 0 && rp == m->pid) sup_.on_heartbeat(m->node, sup_.pid(*i), now_s());
      return;
    }
    sup_.on_heartbeat(m->node, m->pid, now_s());
  }

  void reject(const std::string& node, const std::string& why) {
    log("control request for '" + node + "' rejected: " + why);
    fploc::node_status_t s{};
    s.utime = wall_utime();
    s.node = node;
    s.state = "rejected";
    s.reporter = "launcher";
    s.last_error = "control: " + why;
    s.robot = robot_;
    s.host = host_;
    bus_.lcm().publish(telemetry_, &s);
  }

  void on_control(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_command_t* m) {
    if (listening_only_) return;  // for a launch already running (this one refuses, or starts after its listen)
    const auto i = sup_.find(m->node);
    auto d = decide_control(*m, i ? &table_[*i] : nullptr, g_.graph, hooks_);
    if (d.kind == ControlDecision::Reject) return reject(m->node, d.error);
    if (d.kind == ControlDecision::Stop) {
      log("control: stop node '" + m->node + "'");
      sup_.request_stop(*i, now_s());
      return;
    }
    table_[*i] = std::move(d.entry);
    sup_.set_supervised(*i, table_[*i].fploc_node);
    log("control: " + m->action + " node '" + m->node + "' with " + table_[*i].exe_name +
        (table_[*i].sets.empty() ? "" : " (overrides: " + join(table_[*i].sets) + ")"));
    publish(*i, sup_.pid(*i), sup_.restarts(*i), "restarting", "control: " + m->action);
    sup_.request_restart(*i, now_s());
  }

  LoadedGraph g_;
  std::string robot_, telemetry_, host_ = host_name();
  ValidateHooks hooks_;
  Bus bus_;
  std::map<std::string, std::shared_ptr<const HostPlan>> hosts_;
  struct Master {
    pid_t pid = -1;
    double next_try = 0;
    bool quiet = false;  // its end was reported (or its host is away): not again until it has been up
  };
  std::map<std::string, Master> masters_;  // hosts with at least one node
  ProcessTable table_;
  Supervisor sup_;
  std::vector<std::pair<std::string, std::string>> hosts_down_;
};

void usage() {
  std::cerr << "usage: fploc launch GRAPH.pbtxt [--check] [--skip-hosts] [--wait-for-hosts] [--duration SECONDS] [--lcm-url URL]\n"
               "                                [--set NODE.field=value ...]\n"
               "  --check      validate the graph (fields, executables, ports, channel types, option values, the files options\n"
               "               name) and its hosts (reachable with ssh, fploc there at this commit, multicast route),\n"
               "               then exit (a launch checks the same and refuses to start on an error)\n"
               "  --skip-hosts do not contact the graph's hosts before starting (or in --check)\n"
               "  --wait-for-hosts  a host that does not answer at the start does not stop the launch: the other nodes\n"
               "               start, and that host's nodes start once it answers (the graph's wait_for_hosts: true)\n"
               "  --duration   stop every node cleanly after SECONDS\n"
               "  --set        override one option of one node for this run (e.g. --set pose_logger.file=run1.tum)\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::string graph_path, url;
  std::vector<std::string> sets;
  bool check = false, skip_hosts = false, wait_for_hosts = false;
  double duration = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--check") check = true;
    else if (a == "--skip-hosts") skip_hosts = true;
    else if (a == "--wait-for-hosts") wait_for_hosts = true;
    else if (a == "--duration" && i + 1 < argc) {
      // Strictly a number > 0: atof read "ten" or "nan" as 0, which ran the graph until Ctrl-C.
      const std::string v = argv[++i];
      char* end = nullptr;
      duration = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !std::isfinite(duration) || !(duration > 0)) {
        std::cerr << "fploc launch: --duration " << v << ": expected a number of seconds > 0\n";
        return 2;
      }
    }
    else if (a == "--lcm-url" && i + 1 < argc) url = argv[++i];
    else if (a == "--set" && i + 1 < argc) sets.push_back(argv[++i]);
    else if (a == "-h" || a == "--help") { usage(); return 0; }
    else if (!a.empty() && a[0] != '-' && graph_path.empty()) graph_path = a;
    else { std::cerr << "fploc launch: unexpected argument '" << a << "'\n"; usage(); return 2; }
  }
  if (graph_path.empty()) { usage(); return 2; }

  LoadedGraph g;
  std::vector<GraphError> errors;
  load_graph(graph_path, g, errors);
  const ValidateHooks hooks = default_hooks(self_bin_dir());
  std::string set_error;
  if (g.tree && !apply_node_overrides(g.graph, sets, [&](const fploc::Node& n) {
        const std::string exe = hooks.resolve(n.executable());
        return exe.empty() ? std::string() : hooks.describe(exe).spec.options_field;
      }, set_error))
    errors.push_back({graph_path, 0, set_error});
  std::vector<ResolvedNode> resolved;
  if (g.tree) validate_graph(g, hooks, errors, &resolved);
  url = graph_lcm_url(g.graph, url);
  // The files the options name and the values the nodes would refuse: checked before anything starts, by `--check`
  // and by a launch alike (a launch with a missing plan ran every other node while the matcher died five times).
  if (g.tree) check_option_files(g, errors, /*skip_remote=*/!check);  // a launch: remote nodes' files are on their host
  if (g.tree) check_option_values(g, errors);
  // The hosts, by --check and by a launch alike (a launch used to start its remote nodes without asking, and they
  // ended dead after five failed ssh sessions): one ssh round trip each. A host that does not answer is an error
  // naming its nodes, unless the launch is to wait for it (--wait-for-hosts, Graph.wait_for_hosts).
  wait_for_hosts = wait_for_hosts || (g.tree && g.graph.wait_for_hosts());
  std::vector<std::pair<std::string, std::string>> hosts_down;  // host, why
  std::vector<std::string> warnings;
  if (!skip_hosts && g.tree && errors.empty() && g.graph.host_size() > 0) {
    std::vector<HostPlan> plans;
    const auto by_name = host_plans(g.graph, self_bin_dir());
    for (const auto& h : g.graph.host())  // in the graph's order: check_hosts reports in the order it is given
      if (const auto it = by_name.find(h.name()); it != by_name.end()) plans.push_back(*it->second);
    std::vector<std::pair<std::string, std::string>> host_exe;
    std::map<std::string, std::vector<std::string>> nodes_on;
    for (const auto& rn : resolved) {
      const auto& n = g.graph.node(rn.index);
      if (n.disabled() || n.host().empty()) continue;
      host_exe.push_back({n.host(), rn.executable.empty() ? n.executable() : rn.executable});
      nodes_on[n.host()].push_back(n.name());
    }
    auto its_nodes = [&](const std::string& host) {  // "its nodes 'a', 'b'"
      std::string s;
      for (const auto& name : nodes_on[host]) s += (s.empty() ? "'" : ", '") + name + "'";
      return (nodes_on[host].size() == 1 ? "its node " : "its nodes ") + s;
    };
    for (const auto& p : check_hosts(g.graph, plans, host_exe, url)) {
      const std::string line = "host '" + p.host + "': " + p.message;
      if (!p.unreachable) {
        errors.push_back({graph_path, 0, line});
      } else if (!check && wait_for_hosts) {
        warnings.push_back(graph_path + ": warning: " + line + "; " + its_nodes(p.host) +
                           " will start once it answers (waiting for hosts)");
        hosts_down.push_back({p.host, p.message});
      } else {
        errors.push_back({graph_path, 0, line + "; " + its_nodes(p.host) + " cannot start" +
                                             (check ? "" : " (--wait-for-hosts, or wait_for_hosts: true in the graph, "
                                                           "starts the others and waits for it)")});
      }
    }
  }
  int enabled = 0;
  for (const auto& n : g.graph.node()) enabled += !n.disabled();
  if (g.tree && errors.empty() && enabled == 0)
    errors.push_back({graph_path, 0, g.graph.node_size() == 0 ? "no node: the graph declares none (an empty or wrong file?)"
                                                            : "no node to run: every node is disabled"});
  if (!check && url.rfind("memq://", 0) == 0)
    errors.push_back({graph_path, 0, "lcm_url memq:// only works inside one process (use fploc replay)"});
  std::stable_sort(errors.begin(), errors.end(), [](const GraphError& a, const GraphError& b) {
    return a.file == b.file ? a.line < b.line : a.file < b.file;
  });
  for (const auto& e : errors) std::cerr << e.str() << "\n";
  if (!errors.empty()) {
    std::cerr << graph_path << ": " << errors.size() << " error" << (errors.size() > 1 ? "s" : "") << "\n";
    return 1;
  }
  if (check) {
    std::cerr << graph_path << ": OK (" << enabled << " nodes)\n";
    return 0;
  }
  for (const auto& w : warnings) std::cerr << w << "\n";

  if (::pipe2(g_sig_pipe, O_CLOEXEC | O_NONBLOCK) != 0) return 1;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);
  sigaction(SIGCHLD, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);
  try {
    Launcher l(std::move(g), resolved, url, self_bin_dir(), sets, hosts_down);
    return l.run(duration);
  } catch (const std::exception& e) {
    std::cerr << "fploc launch: " << e.what() << "\n";
    return 1;
  }
}
