// The launcher's supervision policy, as pure logic: which node to start, signal, restart or declare
// hung/dead, and in which order the graph stops. No process calls and no clock here: times come in as
// arguments and every effect goes out through `Effects`, so the policy is unit-tested with a fake clock
// (tools/launch/test/supervisor_test.cpp). The process table (process_table.h) and the control channel
// (control.h) are the launcher's other two parts.
#pragma once
#include <sys/types.h>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fploc/runtime/restart.h"
#include "graph.pb.h"

namespace fploc::launch {

// WaitingForHost: a remote node whose ssh session failed in a way its host's absence explains (ssh's own exit
// code 255: connection refused, timed out or lost; or silence) while the host does not answer a probe. It
// spends no restart budget; the supervisor probes the host with backoff and starts the node when it answers.
enum class State { Starting, Running, Backoff, Stopping, Stopped, Dead, WaitingForHost };
const char* state_name(State s);

// What the supervisor needs to know of one node of the graph.
struct NodePolicy {
  std::string name;
  fploc::RestartPolicy restart;
  double heartbeat_timeout_s = 3.0;  // a running node silent for longer is killed and restarted
  bool supervised = false;           // sends heartbeats (an fploc node); foreign programs are not watched
  std::vector<std::string> inputs;   // channels it consumes (for the stop order)
  std::vector<std::string> outputs;  // channels it produces
  // Runs on another host through ssh: the process the launcher starts is the ssh session, and the node
  // itself exists only once the far end says so (on_remote_started). The login shell there may take
  // seconds (slow rc files, a loaded host), so until then the session-start bound applies, not the
  // heartbeat grace.
  bool remote = false;
  std::string host;  // Graph.host name of a remote node (what its waits and probes are about)
};

// How a process ended (from waitpid).
struct ExitStatus {
  bool exited = true;  // false: killed by `signal`
  int code = 0;
  int signal = 0;
  std::string str() const;  // "exited with code 3" / "killed by signal 9 (Killed)"
  bool failed() const { return !exited || code != 0; }
};

// The outside world as the supervisor sees it.
class Effects {
 public:
  virtual ~Effects() = default;
  // Starts node i (FPLOC_RESTARTS=restarts); returns its process (group) id, or -1 when it could not start.
  virtual pid_t start(size_t i, int restarts) = 0;
  // Sends `sig` to node i's process group.
  virtual void signal(size_t i, pid_t pid, int sig) = 0;
  // node_status_t with reporter "launcher".
  virtual void publish(size_t i, pid_t pid, int restarts, const std::string& state, const std::string& error) = 0;
  virtual void log(const std::string& line) = 0;
  // Contacts `host` (a fresh ssh connection, not the multiplexed one) without blocking; the answer comes back
  // through Supervisor::on_host_probe.
  virtual void probe_host(const std::string& host) = 0;
};

struct SupervisorConfig {
  double shutdown_timeout_s = 2.0;  // SIGINT ... SIGTERM after this, SIGKILL 1 s later
  double stage_gap_s = 0.25;        // graph-wide stop: next rank after this even if the previous still runs
  double first_beat_grace_s = 10.0; // until its first heartbeat a node may be loading (maps)
  double remote_start_s = 60.0;     // a remote node's ssh session must start the node within this
  double report_period_s = 1.0;     // dead/restarting/waiting nodes are re-published this often
  // A host its nodes wait for is probed after host_probe_initial_s, then twice as long each time it does not
  // answer, at most every host_probe_max_s.
  double host_probe_initial_s = 0.5;
  double host_probe_max_s = 2.0;  // + ssh's ConnectTimeout (3 s) while the host is silent
  std::vector<std::string> ignored_channels;  // telemetry/control: not part of the stop order
};

class Supervisor {
 public:
  Supervisor(std::vector<NodePolicy> nodes, SupervisorConfig cfg, Effects& fx);

  // ---- inputs
  // Before start_all: `host` did not answer the launch's check (the graph or the command line asked to wait for
  // it): start_all leaves its nodes waiting for it. `why`: the check's message.
  void host_down_at_start(const std::string& host, const std::string& why, double t);
  void start_all(double t);
  // The answer to Effects::probe_host: the host answered (ssh ran a command there), or not (`why`).
  void on_host_probe(const std::string& host, bool reachable, const std::string& why, double t);
  // A process ended (reaped). Returns false when the pid is not one of ours.
  bool on_exit(pid_t pid, const ExitStatus& st, double t);
  // The far end of remote node i started the node process (fploc-remote reported its pid): the
  // heartbeat grace counts from here.
  void on_remote_started(size_t i, double t);
  // A heartbeat (node_status_t with reporter "node") arrived from `pid` of node `name`.
  void on_heartbeat(const std::string& name, pid_t pid, double t);
  // Any telemetry arrived (the launcher's own too): the transport works here.
  void on_transport_ok() { transport_ok_ = true; }
  // Control requests: stop node i; stop it (if running) and start it again (fresh restart window).
  void request_stop(size_t i, double t);
  void request_restart(size_t i, double t);
  // Graph-wide ordered stop (SIGINT rank by rank, then SIGTERM, SIGKILL).
  void begin_shutdown(double t);
  // Second Ctrl-C: SIGKILL to everything now.
  void kill_all();
  // Escalation, backoff restarts, heartbeat checks, shutdown stages, periodic reports.
  void tick(double t);

  // ---- outputs
  // The launcher's exit code once it should exit (all finished, or shutdown complete), else nothing: 1 when a node
  // ended dead (given up on) during the run or had to be killed at the shutdown, else 0.
  std::optional<int> finished();
  bool shutting_down() const { return shutting_down_; }
  size_t size() const { return nodes_.size(); }
  const std::string& name(size_t i) const { return nodes_[i].policy.name; }
  State state(size_t i) const { return nodes_[i].state; }
  pid_t pid(size_t i) const { return nodes_[i].pid; }
  int restarts(size_t i) const { return nodes_[i].restarts; }
  int stop_rank(size_t i) const { return nodes_[i].stop_rank; }
  std::optional<size_t> find(const std::string& name) const;
  // The host node i waits for ("" when it does not wait).
  std::string waiting_for(size_t i) const {
    return nodes_[i].state == State::WaitingForHost ? nodes_[i].policy.host : std::string();
  }
  // The node now runs another executable (control request): is it heartbeat-supervised?
  void set_supervised(size_t i, bool s) { nodes_[i].policy.supervised = s; }

 private:
  struct Run {
    NodePolicy policy;
    pid_t pid = -1;
    State state = State::Stopped;
    int restarts = 0;
    fploc::rt::RestartTracker tracker;
    double next_start = 0, started_at = 0, last_beat = 0, stop_deadline = 0;
    int stop_stage = 0;  // 0 SIGINT sent, 1 SIGTERM sent, 2 SIGKILL sent
    bool restart_after_stop = false, hung = false;
    bool remote_started = false;  // remote nodes: the far end has started the node process
    int stop_rank = 0;
    bool ever_started = false;
    // WaitingForHost: since when, and the failure that led there. Until a probe has found the host away
    // (host_confirmed) the failure may still be the node's own: if the host answers at once, it is charged to
    // the restart policy as any other.
    bool host_confirmed = false;
    double wait_since = 0, wait_ran = 0;
    std::string wait_why;
  };
  // A host that nodes wait for.
  struct HostWatch {
    bool down = false;        // the last probe (or the launch's check) did not reach it
    bool probing = false;     // a probe is under way
    double next_probe = 0, delay = 0, down_since = 0;
    std::string why;          // what the last failed probe said
  };
  void start(size_t i, double t);
  void begin_stop(size_t i, bool restart_after, double t);
  void escalate(size_t i, double t);
  void check_heartbeat(size_t i, double t);
  void kill_hung(size_t i, double t, const std::string& why, const std::string& error);
  void apply_restart(size_t i, const fploc::rt::RestartDecision& d, const std::string& why, double t);
  void advance_shutdown(double t);
  void rank_for_shutdown();
  void publish(size_t i, const std::string& state, const std::string& error);
  // A failed exit of node i (ended at t_exit after running ran_s): restart with backoff, or dead, or stopped.
  void settle_exit(size_t i, bool failed, const std::string& how, double t_exit, double ran_s, double t);
  void wait_for_host(size_t i, const std::string& why, double ran_s, double t);
  std::string waiting_error(size_t i) const;
  std::string nodes_waiting_on(const std::string& host) const;

  std::vector<Run> nodes_;
  // What makes the launcher's exit code 1 after a shutdown: nodes given up on (dead) during the run, and nodes that
  // had to be killed (SIGKILL: they ignored SIGINT and SIGTERM, or a second Ctrl-C) -- a script must notice both.
  std::vector<std::string> died_, killed_;
  // Nodes still waiting for their host when the shutdown began: they did not run, and the exit code says so.
  std::vector<std::string> waiting_at_shutdown_;
  std::map<std::string, HostWatch> hosts_;
  SupervisorConfig cfg_;
  Effects& fx_;
  bool transport_ok_ = false, transport_warned_ = false;
  bool shutting_down_ = false;
  double shutdown_started_ = 0, stage_started_ = 0, last_report_ = 0;
  int stop_rank_ = -1;
};

std::string fmt2(double v);  // "%.2f"

}  // namespace fploc::launch
