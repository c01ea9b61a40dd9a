// fploc launch: validates a graph (every error as file:line), then runs and supervises its nodes.
//   fploc launch GRAPH [--check] [--duration S] [--lcm-url URL] [--set NODE.field=value ...]
// Each node is its own process (own process group, PR_SET_PDEATHSIG=SIGKILL) started as
//   EXE --graph GRAPH --node NAME [--set k=v ...] [args...]   with FPLOC_RESTARTS=<restarts so far>.
// Supervision: restart policy (never/on-failure/always, max restarts in a window, exponential backoff),
// heartbeat timeout on FPLOC_TELEMETRY (a silent node is killed and restarted), control requests on
// FPLOC_CONTROL (node_command_t from `fploc node restart`). Events go to stderr and, as node_status_t
// with reporter "launcher", to FPLOC_TELEMETRY. SIGINT/SIGTERM (or --duration): SIGINT to every node,
// then SIGTERM, then SIGKILL.
#include <fcntl.h>
#include <fploc/node_command_t.hpp>
#include <fploc/node_status_t.hpp>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
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
#include "fploc/runtime/validate.h"

using namespace fploc::rt;

namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double g_t0 = now_s();
void log(const std::string& msg) {
  char ts[32];
  std::snprintf(ts, sizeof ts, "%8.3f", now_s() - g_t0);
  std::cerr << "[launch " << ts << "] " << msg << std::endl;
}

int g_sig_pipe[2] = {-1, -1};
void on_signal(int sig) {
  const char c = char(sig);
  [[maybe_unused]] auto r = ::write(g_sig_pipe[1], &c, 1);
}

enum class State { Starting, Running, Backoff, Stopping, Stopped, Dead };
const char* state_name(State s) {
  switch (s) {
    case State::Starting: return "starting";
    case State::Running: return "running";
    case State::Backoff: return "restarting";
    case State::Stopping: return "stopping";
    case State::Stopped: return "stopped";
    case State::Dead: return "dead";
  }
  return "?";
}

struct Child {
  std::string name;
  std::string exe_name;               // as in the graph (or the control request)
  std::string exe_path;               // resolved
  bool fploc_node = false;            // speaks the runtime protocol (--graph/--node, telemetry)
  std::string options_field;          // declared by the executable
  NodeSpec spec;                      // its --describe (fploc nodes)
  std::vector<std::string> sets;      // overrides (launch --set, then control requests), field=value
  std::vector<std::string> args;
  fploc::RestartPolicy policy;
  double heartbeat_timeout = 3.0;

  pid_t pid = -1;
  State state = State::Stopped;
  int restarts = 0;                   // FPLOC_RESTARTS of the next start - 1
  RestartTracker tracker;             // window and backoff
  double next_start = 0;
  double started_at = 0;
  double last_beat = 0;               // 0 = none from this pid yet
  double stop_deadline = 0;           // Stopping: next escalation time
  int stop_stage = 0;                 // 0 SIGINT sent, 1 SIGTERM sent, 2 SIGKILL sent
  bool restart_after_stop = false;    // control request: start again once stopped
  bool hung = false;
  int stop_rank = 0;                  // graph-wide stop order: producers before their consumers
};

double policy_or(double v, double d) { return v > 0 ? v : d; }

class Launcher {
 public:
  // `sets`: the command line's NODE.field=value overrides (already checked against the graph).
  Launcher(LoadedGraph g, std::vector<ResolvedNode> resolved, std::string url, std::string bin_dir,
           const std::vector<std::string>& sets)
      : g_(std::move(g)), bin_dir_(std::move(bin_dir)), bus_(url) {
    for (const auto& rn : resolved) {
      const auto& n = g_.graph.node(rn.index);
      if (n.disabled()) continue;
      Child c;
      c.name = n.name();
      c.exe_name = n.executable();
      c.exe_path = rn.executable;
      c.fploc_node = rn.desc.describable;
      c.options_field = rn.desc.spec.options_field;
      c.spec = rn.desc.spec;
      c.args.assign(n.args().begin(), n.args().end());
      c.policy = n.restart();
      c.heartbeat_timeout = policy_or(n.heartbeat_timeout_s(), 3.0);
      c.tracker = RestartTracker(c.policy);
      for (const auto& s : sets)
        if (s.rfind(c.name + ".", 0) == 0) c.sets.push_back(s.substr(c.name.size() + 1));
      children_.push_back(std::move(c));
    }
    shutdown_timeout_ = policy_or(g_.graph.shutdown_timeout_s(), 2.0);
    graph_abs_ = std::filesystem::absolute(g_.path).string();
    bus_.lcm().subscribe(kTelemetryChannel, &Launcher::on_telemetry, this);
    control_channel_ = g_.graph.control_channel().empty() ? kControlChannel : g_.graph.control_channel();
    bus_.lcm().subscribe(control_channel_, &Launcher::on_control, this);
    rank_for_shutdown(resolved);
  }

  int run(double duration) {
    const double t_start = now_s();
    for (auto& c : children_) start(c);
    log("graph '" + g_.graph.name() + "' running: " + std::to_string(children_.size()) + " nodes on " + bus_.url() +
        (duration > 0 ? ", for " + fmt(duration) + " s" : "") + "; control on " + control_channel_);
    bool shutting_down = false;
    double last_report = now_s();
    const int lcm_fd = bus_.lcm().getFileno();
    for (;;) {
      pollfd p[2] = {{lcm_fd, POLLIN, 0}, {g_sig_pipe[0], POLLIN, 0}};
      ::poll(p, 2, 20);
      if (p[0].revents & POLLIN) bus_.lcm().handleTimeout(0);
      if (p[1].revents & POLLIN) {
        char buf[16];
        const ssize_t n = ::read(g_sig_pipe[0], buf, sizeof buf);
        for (ssize_t k = 0; k < n; ++k) {
          if (buf[k] == SIGCHLD) continue;
          if (!shutting_down) {
            log(std::string("received ") + strsignal(buf[k]) + ": stopping every node");
            shutting_down = true;
            begin_stop_all();
          } else {
            log("second signal: killing every node now");
            for (auto& c : children_)
              if (c.pid > 0) ::kill(-c.pid, SIGKILL);
          }
        }
      }
      if (!shutting_down && duration > 0 && now_s() - t_start >= duration) {
        log("duration of " + fmt(duration) + " s reached: stopping every node");
        shutting_down = true;
        begin_stop_all();
      }
      if (shutting_down) advance_stop_all();
      reap();
      const double t = now_s();
      for (auto& c : children_) {
        if (c.state == State::Stopping) escalate(c, t);
        if (shutting_down) continue;
        if (c.state == State::Backoff && t >= c.next_start) start(c);
        if (c.state == State::Running && c.fploc_node) check_heartbeat(c, t);
      }
      if (t - last_report >= 1.0) {
        last_report = t;
        for (auto& c : children_)
          if (c.state == State::Dead || c.state == State::Backoff) publish(c, state_name(c.state), "");
      }
      if (!shutting_down && std::all_of(children_.begin(), children_.end(), [](const Child& c) {
            return c.state == State::Stopped || c.state == State::Dead;
          })) {
        const bool dead = std::any_of(children_.begin(), children_.end(),
                                      [](const Child& c) { return c.state == State::Dead; });
        log(std::string("no node left running (") + (dead ? "some failed" : "all finished") + "): exiting");
        return dead ? 1 : 0;
      }
      if (shutting_down &&
          std::all_of(children_.begin(), children_.end(), [](const Child& c) { return c.pid <= 0; })) {
        log("all nodes stopped");
        for (auto& c : children_) publish(c, "stopped", "");
        return 0;
      }
    }
  }

 private:
  void start(Child& c) {
    std::vector<std::string> args{c.exe_path};
    if (c.fploc_node) {
      args.insert(args.end(), {"--graph", graph_abs_, "--node", c.name});
      for (const auto& s : c.sets) args.insert(args.end(), {"--set", s});
    }
    args.insert(args.end(), c.args.begin(), c.args.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> env_s;
    for (char** e = environ; *e; ++e)
      if (std::strncmp(*e, "FPLOC_RESTARTS=", 15) != 0) env_s.push_back(*e);
    env_s.push_back("FPLOC_RESTARTS=" + std::to_string(c.restarts));
    std::vector<char*> envp;
    for (auto& e : env_s) envp.push_back(e.data());
    envp.push_back(nullptr);
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) {
      log("node '" + c.name + "': fork failed: " + strerror(errno));
      schedule_restart(c, "fork failed");
      return;
    }
    if (pid == 0) {
      ::setpgid(0, 0);
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (::getppid() != parent) ::_exit(127);  // the launcher died before prctl
      sigset_t none;
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      for (int s : {SIGINT, SIGTERM, SIGCHLD, SIGPIPE}) ::signal(s, SIG_DFL);
      ::syscall(SYS_close_range, 3u, ~0u, 0u);
      ::execve(argv[0], argv.data(), envp.data());
      const char msg[] = "fploc launch: exec failed\n";
      [[maybe_unused]] auto r = ::write(2, msg, sizeof msg - 1);
      ::_exit(127);
    }
    ::setpgid(pid, pid);  // also from the parent: no race with kill(-pid)
    c.pid = pid;
    c.state = State::Running;
    c.started_at = now_s();
    c.last_beat = 0;
    c.hung = false;
    publish(c, "starting", "");
    log("node '" + c.name + "' started: pid " + std::to_string(pid) + ", " + c.exe_name +
        (c.sets.empty() ? "" : " (overrides: " + join(c.sets) + ")") +
        (c.restarts ? ", restart " + std::to_string(c.restarts) : ""));
  }

  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : " ") + x;
    return s;
  }

  // Stop order for the whole graph: a node's rank is one more than the highest rank of the nodes that
  // produce its inputs (telemetry and control excluded; cycles are cut after N rounds), so sources stop
  // first and every node still receives what its producers publish while they shut down (the
  // optimizer's last window reaches the pose logger).
  void rank_for_shutdown(const std::vector<ResolvedNode>& resolved) {
    std::map<std::string, std::vector<size_t>> producers;  // channel -> children
    std::vector<std::vector<std::string>> inputs(children_.size());
    auto channel_of = [](const fploc::Node& n, const PortSpec& s) {
      for (const auto& p : s.output ? n.output() : n.input())
        if (p.port() == s.name) return p.channel();
      return s.default_channel;
    };
    size_t k = 0;
    for (const auto& rn : resolved) {
      const auto& n = g_.graph.node(rn.index);
      if (n.disabled()) continue;
      for (const auto& s : rn.desc.spec.ports) {
        const std::string ch = channel_of(n, s);
        if (ch.empty() || ch == kTelemetryChannel || ch == control_channel_) continue;
        if (s.output) producers[ch].push_back(k);
        else inputs[k].push_back(ch);
      }
      ++k;
    }
    for (size_t round = 0; round < children_.size(); ++round) {
      bool changed = false;
      for (size_t i = 0; i < children_.size(); ++i)
        for (const auto& ch : inputs[i])
          for (size_t p : producers[ch])
            if (p != i && children_[p].stop_rank + 1 > children_[i].stop_rank) {
              children_[i].stop_rank = children_[p].stop_rank + 1;
              changed = true;
            }
      if (!changed) break;
    }
  }
  // Graph-wide stop: SIGINT rank by rank; the next rank goes when the previous has exited or after
  // 0.25 s. Escalation (SIGTERM, then SIGKILL) counts from the start of the stop, so a hung node costs
  // at most shutdown_timeout_s + 1 s in all.
  void begin_stop_all() {
    stop_all_started_ = now_s();
    stop_rank_ = -1;
    stage_started_ = 0;
    advance_stop_all();
  }
  void advance_stop_all() {
    int max_rank = 0;
    for (const auto& c : children_) max_rank = std::max(max_rank, c.stop_rank);
    const double t = now_s();
    while (stop_rank_ <= max_rank) {
      const bool stage_done = std::all_of(children_.begin(), children_.end(), [&](const Child& c) {
        return c.stop_rank > stop_rank_ || c.pid <= 0;
      });
      const bool late = t >= stop_all_started_ + shutdown_timeout_;
      if (stop_rank_ >= 0 && !stage_done && !late && t - stage_started_ < 0.25) return;
      ++stop_rank_;
      stage_started_ = t;
      for (auto& c : children_)
        if (c.stop_rank == stop_rank_) {
          begin_stop(c, false);
          c.stop_deadline = std::max(stop_all_started_ + shutdown_timeout_, t + 0.1);
        }
    }
  }

  void begin_stop(Child& c, bool restart_after) {
    c.restart_after_stop = restart_after;
    if (c.pid <= 0) {
      if (!restart_after) c.state = State::Stopped;
      return;
    }
    if (c.state == State::Stopping) return;
    c.state = State::Stopping;
    c.stop_stage = 0;
    c.stop_deadline = now_s() + shutdown_timeout_;
    ::kill(-c.pid, SIGINT);
  }

  void escalate(Child& c, double t) {
    if (c.pid <= 0 || t < c.stop_deadline) return;
    if (c.stop_stage == 0) {
      log("node '" + c.name + "' still running " + fmt(shutdown_timeout_) + " s after SIGINT: SIGTERM");
      ::kill(-c.pid, SIGTERM);
      c.stop_stage = 1;
      c.stop_deadline = t + 1.0;
    } else if (c.stop_stage == 1) {
      log("node '" + c.name + "' ignores SIGTERM: SIGKILL");
      ::kill(-c.pid, SIGKILL);
      c.stop_stage = 2;
      c.stop_deadline = t + 1e9;
    }
  }

  void check_heartbeat(Child& c, double t) {
    // Until the first heartbeat the node may still be loading (maps): allow a longer grace period.
    const double since = c.last_beat > 0 ? t - c.last_beat : t - c.started_at;
    const double limit = c.last_beat > 0 ? c.heartbeat_timeout : std::max(c.heartbeat_timeout, 10.0);
    if (since <= limit) return;
    if (c.last_beat == 0 && !transport_ok_) {
      if (!transport_warned_)
        log("warning: no telemetry arrives on " + bus_.url() +
            " (not even the launcher's own): heartbeat supervision is off until the first heartbeat");
      transport_warned_ = true;
      return;
    }
    log("node '" + c.name + "' (pid " + std::to_string(c.pid) + ") hung: no heartbeat for " + fmt(since) +
        " s; killing it");
    c.hung = true;
    publish(c, "hung", "no heartbeat for " + fmt(since) + " s");
    ::kill(-c.pid, SIGKILL);
    c.state = State::Stopping;
    c.stop_stage = 2;
    c.stop_deadline = t + 1e9;
  }

  static std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
  }

  void reap() {
    for (;;) {
      int status = 0;
      const pid_t pid = ::waitpid(-1, &status, WNOHANG);
      if (pid <= 0) return;
      for (auto& c : children_) {
        if (c.pid != pid) continue;
        // Anything left in the node's process group goes with it.
        ::kill(-pid, SIGKILL);
        c.pid = -1;
        std::string how = WIFEXITED(status) ? "exited with code " + std::to_string(WEXITSTATUS(status))
                                            : "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
        const bool failed = c.hung || !WIFEXITED(status) || WEXITSTATUS(status) != 0;
        if (c.state == State::Stopping && !c.hung) {
          log("node '" + c.name + "' stopped (" + how + ")");
          if (c.restart_after_stop) {
            c.restart_after_stop = false;
            ++c.restarts;
            start(c);
          } else {
            c.state = State::Stopped;
          }
          break;
        }
        const auto d = c.tracker.on_exit(now_s(), now_s() - c.started_at, failed);
        if (!d.restart && !d.give_up) {
          log("node '" + c.name + "' " + how + (failed ? " (restart policy: not restarted)" : ""));
          c.state = failed ? State::Dead : State::Stopped;
          publish(c, failed ? "dead" : "stopped", how);
        } else {
          apply_restart(c, d, (c.hung ? "hung, " : "") + how);
        }
        break;
      }
    }
  }

  void schedule_restart(Child& c, const std::string& why) {
    apply_restart(c, c.tracker.on_exit(now_s(), now_s() - c.started_at, true), why);
  }

  void apply_restart(Child& c, const RestartDecision& d, const std::string& why) {
    if (!d.restart) {
      log("node '" + c.name + "' " + why + ": " + std::to_string(d.max_restarts) + " restarts within " +
          fmt(d.window_s) + " s already, giving up (dead)");
      c.state = State::Dead;
      publish(c, "dead", why + "; too many restarts");
      return;
    }
    ++c.restarts;
    c.next_start = now_s() + d.delay;
    c.state = State::Backoff;
    log("node '" + c.name + "' " + why + "; restarting in " + fmt(d.delay) + " s (restart " +
        std::to_string(c.restarts) + ", " + std::to_string(d.in_window) + "/" + std::to_string(d.max_restarts) +
        " within " + fmt(d.window_s) + " s)");
    publish(c, "restarting", why);
  }

  void publish(const Child& c, const std::string& state, const std::string& error) {
    fploc::node_status_t s{};
    s.utime = wall_utime();
    s.node = c.name;
    s.executable = c.exe_name;
    s.pid = c.pid;
    s.state = state;
    s.reporter = "launcher";
    s.restarts = c.restarts;
    s.last_error = error;
    s.num_ports = 0;
    bus_.lcm().publish(kTelemetryChannel, &s);
  }

  Child* find(const std::string& name) {
    for (auto& c : children_)
      if (c.name == name) return &c;
    return nullptr;
  }

  void on_telemetry(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) {
    transport_ok_ = true;  // our own "starting" reports come back too when the LCM URL works here
    if (m->reporter == "launcher") return;
    Child* c = find(m->node);
    if (c && c->pid > 0 && m->pid == c->pid) c->last_beat = now_s();
  }

  void reject(const std::string& node, const std::string& why) {
    log("control request for '" + node + "' rejected: " + why);
    fploc::node_status_t s{};
    s.utime = wall_utime();
    s.node = node;
    s.state = "rejected";
    s.reporter = "launcher";
    s.last_error = "control: " + why;
    bus_.lcm().publish(kTelemetryChannel, &s);
  }

  void on_control(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_command_t* m) {
    if (!g_.graph.control_token().empty() && m->token != g_.graph.control_token()) {
      reject(m->node, "wrong control token");
      return;
    }
    Child* c = find(m->node);
    if (!c) {
      reject(m->node, "no running node named '" + m->node + "'");
      return;
    }
    if (m->action == "stop") {
      log("control: stop node '" + c->name + "'");
      begin_stop(*c, false);
      publish(*c, "stopping", "");
      return;
    }
    if (m->action != "restart" && m->action != "start") {
      reject(m->node, "unknown action '" + m->action + "' (restart, stop, start)");
      return;
    }
    // A new executable / overrides must pass the same checks as the graph before the old one stops.
    std::string exe_name = c->exe_name, exe_path = c->exe_path, field = c->options_field;
    bool fploc_node = c->fploc_node;
    NodeSpec spec = c->spec;
    if (!m->executable.empty() && m->executable != c->exe_name) {
      exe_path = resolve_executable(m->executable, bin_dir_);
      if (exe_path.empty()) return reject(m->node, "executable '" + m->executable + "' not found");
      auto d = describe_executable(exe_path);
      if (!d.error.empty()) return reject(m->node, d.error);
      const auto& n = graph_node(c->name);
      const std::string graph_field = node_options_field(n);
      if (d.describable && !graph_field.empty() && graph_field != d.spec.options_field)
        return reject(m->node, "'" + m->executable + "' takes options '" + d.spec.options_field +
                                   "' but the graph gives '" + graph_field + "'");
      // The swapped-in module must offer the ports the graph maps, with the same LCM types as before.
      if (d.describable && c->fploc_node) {
        for (const auto& old_p : c->spec.ports) {
          const PortSpec* np = nullptr;
          for (const auto& p : d.spec.ports)
            if (p.name == old_p.name && p.output == old_p.output) np = &p;
          if (!np)
            return reject(m->node, "'" + m->executable + "' has no " + (old_p.output ? "output" : "input") +
                                       " port '" + old_p.name + "' (the running " + c->exe_name + " has)");
          if (np->lcm_type != old_p.lcm_type)
            return reject(m->node, "'" + m->executable + "' port '" + np->name + "' is " + np->lcm_type +
                                       ", the graph's channel carries " + old_p.lcm_type);
        }
      }
      exe_name = m->executable;
      spec = d.spec;
      fploc_node = d.describable;
      field = d.spec.options_field;
    }
    std::vector<std::string> sets(m->set.begin(), m->set.end());
    if (!sets.empty()) {
      if (!fploc_node) return reject(m->node, "--set needs an fploc node");
      auto opts = node_options(graph_node(c->name));
      if (!opts) opts = default_options(field);
      if (!opts) return reject(m->node, "node takes no options");
      std::string err;
      auto all = c->sets;
      all.insert(all.end(), sets.begin(), sets.end());
      if (!apply_overrides(*opts, all, err)) return reject(m->node, err);
      sets = all;
    } else {
      sets = c->sets;
    }
    if (exe_name != c->exe_name) sets = std::vector<std::string>(m->set.begin(), m->set.end());
    c->exe_name = exe_name;
    c->exe_path = exe_path;
    c->fploc_node = fploc_node;
    c->options_field = field;
    c->spec = spec;
    c->sets = sets;
    c->tracker.reset();
    log("control: " + m->action + " node '" + c->name + "' with " + exe_name +
        (sets.empty() ? "" : " (overrides: " + join(sets) + ")"));
    publish(*c, "restarting", "control: " + m->action);
    if (c->pid > 0) {
      begin_stop(*c, true);
    } else {
      if (c->started_at > 0) ++c->restarts;
      start(*c);
    }
  }

  const fploc::Node& graph_node(const std::string& name) const {
    for (const auto& n : g_.graph.node())
      if (n.name() == name) return n;
    static const fploc::Node empty;
    return empty;
  }

  LoadedGraph g_;
  std::string bin_dir_;
  Bus bus_;
  std::vector<Child> children_;
  double shutdown_timeout_ = 2.0;
  bool transport_ok_ = false, transport_warned_ = false;
  std::string graph_abs_, control_channel_;
  double stop_all_started_ = 0, stage_started_ = 0;
  int stop_rank_ = -1;
};

void usage() {
  std::cerr << "usage: fploc launch GRAPH.pbtxt [--check] [--duration SECONDS] [--lcm-url URL] [--set NODE.field=value ...]\n"
               "  --check      validate the graph (fields, executables, ports, channel types) and exit\n"
               "  --duration   stop every node cleanly after SECONDS\n"
               "  --set        override one option of one node for this run (e.g. --set pose_logger.file=run1.tum)\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::string graph_path, url;
  std::vector<std::string> sets;
  bool check = false;
  double duration = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--check") check = true;
    else if (a == "--duration" && i + 1 < argc) duration = std::atof(argv[++i]);
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
  if (url.empty()) url = g.graph.lcm_url();
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
    int enabled = 0;
    for (const auto& n : g.graph.node()) enabled += !n.disabled();
    std::cerr << graph_path << ": OK (" << enabled << " nodes)\n";
    return 0;
  }

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
    Launcher l(std::move(g), std::move(resolved), url, self_bin_dir(), sets);
    return l.run(duration);
  } catch (const std::exception& e) {
    std::cerr << "fploc launch: " << e.what() << "\n";
    return 1;
  }
}
