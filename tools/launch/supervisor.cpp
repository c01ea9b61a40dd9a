#include "supervisor.h"

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>

namespace fploc::launch {

const char* state_name(State s) {
  switch (s) {
    case State::Starting: return "starting";
    case State::Running: return "running";
    case State::Backoff: return "restarting";
    case State::Stopping: return "stopping";
    case State::Stopped: return "stopped";
    case State::Dead: return "dead";
    case State::WaitingForHost: return "waiting";
  }
  return "?";
}

std::string fmt2(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

std::string ExitStatus::str() const {
  if (exited) return "exited with code " + std::to_string(code);
  return "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
}

Supervisor::Supervisor(std::vector<NodePolicy> nodes, SupervisorConfig cfg, Effects& fx) : cfg_(std::move(cfg)), fx_(fx) {
  for (auto& p : nodes) {
    Run r;
    r.tracker = fploc::rt::RestartTracker(p.restart);
    r.policy = std::move(p);
    nodes_.push_back(std::move(r));
  }
  rank_for_shutdown();
}

std::optional<size_t> Supervisor::find(const std::string& name) const {
  for (size_t i = 0; i < nodes_.size(); ++i)
    if (nodes_[i].policy.name == name) return i;
  return std::nullopt;
}

void Supervisor::publish(size_t i, const std::string& state, const std::string& error) {
  fx_.publish(i, nodes_[i].pid, nodes_[i].restarts, state, error);
}

std::string Supervisor::nodes_waiting_on(const std::string& host) const {
  std::string s;
  int count = 0;
  for (const auto& n : nodes_)
    if (n.state == State::WaitingForHost && n.policy.host == host) {
      s += (s.empty() ? "'" : ", '") + n.policy.name + "'";
      ++count;
    }
  return (count == 1 ? "node " : "nodes ") + s;
}

std::string Supervisor::waiting_error(size_t i) const {
  const auto& n = nodes_[i];
  const auto h = hosts_.find(n.policy.host);
  if (n.host_confirmed && h != hosts_.end())
    return "waiting for host '" + n.policy.host + "': " + h->second.why;
  return "checking host '" + n.policy.host + "' after: " + (n.hung ? "hung, " : "") + n.wait_why;
}

void Supervisor::host_down_at_start(const std::string& host, const std::string& why, double t) {
  auto& h = hosts_[host];
  h.down = true;
  h.down_since = t;
  h.why = why;
  h.delay = cfg_.host_probe_initial_s;
  h.next_probe = t + h.delay;
}

void Supervisor::start_all(double t) {
  for (size_t i = 0; i < nodes_.size(); ++i) {
    auto& n = nodes_[i];
    const auto h = hosts_.find(n.policy.host);
    if (n.policy.host.empty() || h == hosts_.end() || !h->second.down) {
      start(i, t);
      continue;
    }
    n.state = State::WaitingForHost;
    n.host_confirmed = true;
    n.wait_since = t;
    n.wait_ran = 0;
    n.wait_why = "not started";
    publish(i, "waiting", waiting_error(i));
  }
  for (const auto& [name, h] : hosts_)
    if (h.down)
      fx_.log("host '" + name + "' " + h.why + ": " + nodes_waiting_on(name) + " waiting for host '" + name +
              "'; probing it in " + fmt2(h.delay) + " s, then with backoff (at most every " +
              fmt2(cfg_.host_probe_max_s) + " s)");
}

void Supervisor::start(size_t i, double t) {
  auto& n = nodes_[i];
  n.ever_started = true;
  const pid_t pid = fx_.start(i, n.restarts);
  n.started_at = t;
  if (pid <= 0) {
    apply_restart(i, n.tracker.on_exit(t, 0, true), "could not start", t);
    return;
  }
  n.pid = pid;
  n.state = State::Running;
  n.last_beat = 0;
  n.hung = false;
  n.remote_started = false;
  publish(i, "starting", "");
}

void Supervisor::on_remote_started(size_t i, double t) {
  auto& n = nodes_[i];
  if (n.remote_started || n.state != State::Running) return;
  n.remote_started = true;
  n.started_at = t;
}

// Stop order for the whole graph: a node's rank is one more than the highest rank of the nodes that
// produce its inputs (telemetry and control excluded; cycles are cut after N rounds), so sources stop
// first and every node still receives what its producers publish while they shut down (the
// optimizer's last window reaches the pose logger).
void Supervisor::rank_for_shutdown() {
  auto ignored = [&](const std::string& ch) {
    return ch.empty() ||
           std::find(cfg_.ignored_channels.begin(), cfg_.ignored_channels.end(), ch) != cfg_.ignored_channels.end();
  };
  std::map<std::string, std::vector<size_t>> producers;
  for (size_t k = 0; k < nodes_.size(); ++k)
    for (const auto& ch : nodes_[k].policy.outputs)
      if (!ignored(ch)) producers[ch].push_back(k);
  for (size_t round = 0; round < nodes_.size(); ++round) {
    bool changed = false;
    for (size_t i = 0; i < nodes_.size(); ++i)
      for (const auto& ch : nodes_[i].policy.inputs) {
        if (ignored(ch)) continue;
        for (size_t p : producers[ch])
          if (p != i && nodes_[p].stop_rank + 1 > nodes_[i].stop_rank) {
            nodes_[i].stop_rank = nodes_[p].stop_rank + 1;
            changed = true;
          }
      }
    if (!changed) break;
  }
}

// Graph-wide stop: SIGINT rank by rank; the next rank goes when the previous has exited or after
// stage_gap_s. Escalation (SIGTERM, then SIGKILL) counts from the start of the stop, so a hung node costs
// at most shutdown_timeout_s + 1 s in all.
void Supervisor::begin_shutdown(double t) {
  if (shutting_down_) return;
  for (const auto& n : nodes_)
    if (n.state == State::WaitingForHost) waiting_at_shutdown_.push_back(n.policy.name);
  shutting_down_ = true;
  shutdown_started_ = t;
  stop_rank_ = -1;
  stage_started_ = 0;
  advance_shutdown(t);
}

void Supervisor::advance_shutdown(double t) {
  int max_rank = 0;
  for (const auto& n : nodes_) max_rank = std::max(max_rank, n.stop_rank);
  while (stop_rank_ <= max_rank) {
    const bool stage_done = std::all_of(nodes_.begin(), nodes_.end(),
                                        [&](const Run& n) { return n.stop_rank > stop_rank_ || n.pid <= 0; });
    const bool late = t >= shutdown_started_ + cfg_.shutdown_timeout_s;
    if (stop_rank_ >= 0 && !stage_done && !late && t - stage_started_ < cfg_.stage_gap_s) return;
    ++stop_rank_;
    stage_started_ = t;
    for (size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].stop_rank == stop_rank_) {
        begin_stop(i, false, t);
        nodes_[i].stop_deadline = std::max(shutdown_started_ + cfg_.shutdown_timeout_s, t + 0.1);
      }
  }
}

void Supervisor::kill_all() {
  for (size_t i = 0; i < nodes_.size(); ++i)
    if (nodes_[i].pid > 0) {
      fx_.signal(i, nodes_[i].pid, SIGKILL);
      if (std::find(killed_.begin(), killed_.end(), nodes_[i].policy.name) == killed_.end())
        killed_.push_back(nodes_[i].policy.name);
    }
}

void Supervisor::begin_stop(size_t i, bool restart_after, double t) {
  auto& n = nodes_[i];
  n.restart_after_stop = restart_after;
  if (n.pid <= 0) {
    if (!restart_after) n.state = State::Stopped;
    return;
  }
  if (n.state == State::Stopping) return;
  n.state = State::Stopping;
  n.stop_stage = 0;
  n.stop_deadline = t + cfg_.shutdown_timeout_s;
  fx_.signal(i, n.pid, SIGINT);
}

void Supervisor::escalate(size_t i, double t) {
  auto& n = nodes_[i];
  if (n.pid <= 0 || t < n.stop_deadline) return;
  if (n.stop_stage == 0) {
    fx_.log("node '" + n.policy.name + "' still running " + fmt2(cfg_.shutdown_timeout_s) + " s after SIGINT: SIGTERM");
    fx_.signal(i, n.pid, SIGTERM);
    n.stop_stage = 1;
    n.stop_deadline = t + 1.0;
  } else if (n.stop_stage == 1) {
    fx_.log("node '" + n.policy.name + "' ignores SIGTERM: SIGKILL");
    fx_.signal(i, n.pid, SIGKILL);
    killed_.push_back(n.policy.name);
    n.stop_stage = 2;
    n.stop_deadline = t + 1e9;
  }
}

void Supervisor::on_heartbeat(const std::string& name, pid_t pid, double t) {
  transport_ok_ = true;
  auto i = find(name);
  if (i && nodes_[*i].pid > 0 && nodes_[*i].pid == pid) nodes_[*i].last_beat = t;
}

void Supervisor::check_heartbeat(size_t i, double t) {
  auto& n = nodes_[i];
  if (n.policy.remote && !n.remote_started) {
    const double waited = t - n.started_at;
    if (waited <= cfg_.remote_start_s) return;
    kill_hung(i, t, "its ssh session did not start the node within " + fmt2(waited) +
                        " s (the host's login shell or fploc-remote hangs)",
              "ssh session did not start the node within " + fmt2(waited) + " s");
    return;
  }
  // Until the first heartbeat the node may still be loading (maps): allow a longer grace period.
  const double since = n.last_beat > 0 ? t - n.last_beat : t - n.started_at;
  const double limit = n.last_beat > 0 ? n.policy.heartbeat_timeout_s
                                       : std::max(n.policy.heartbeat_timeout_s, cfg_.first_beat_grace_s);
  if (since <= limit) return;
  if (n.last_beat == 0 && !transport_ok_) {
    if (!transport_warned_)
      fx_.log("warning: no telemetry arrives (not even the launcher's own): heartbeat supervision is off until "
              "the first heartbeat");
    transport_warned_ = true;
    return;
  }
  kill_hung(i, t, "hung: no heartbeat for " + fmt2(since) + " s", "no heartbeat for " + fmt2(since) + " s");
}

void Supervisor::kill_hung(size_t i, double t, const std::string& why, const std::string& error) {
  auto& n = nodes_[i];
  fx_.log("node '" + n.policy.name + "' (pid " + std::to_string(n.pid) + ") " + why + "; killing it");
  n.hung = true;
  publish(i, "hung", error);
  fx_.signal(i, n.pid, SIGKILL);
  n.state = State::Stopping;
  n.stop_stage = 2;
  n.stop_deadline = t + 1e9;
}

bool Supervisor::on_exit(pid_t pid, const ExitStatus& st, double t) {
  for (size_t i = 0; i < nodes_.size(); ++i) {
    auto& n = nodes_[i];
    if (n.pid != pid) continue;
    // Anything left in the node's process group goes with it.
    fx_.signal(i, pid, SIGKILL);
    n.pid = -1;
    const std::string how = st.str();
    const bool failed = n.hung || st.failed();
    if (n.state == State::Stopping && !n.hung) {
      fx_.log("node '" + n.policy.name + "' stopped (" + how + ")");
      if (n.restart_after_stop && !shutting_down_) {
        n.restart_after_stop = false;
        ++n.restarts;
        start(i, t);
      } else {
        n.state = State::Stopped;
      }
      return true;
    }
    if (shutting_down_) {
      n.state = State::Stopped;
      fx_.log("node '" + n.policy.name + "' " + how);
      return true;
    }
    // A remote node's session ended with ssh's own failure code (connection refused, timed out or lost), or the
    // node went silent: its host may be away. That is found out (a probe) before the restart budget is spent.
    if (failed && n.policy.remote && !n.policy.host.empty() && (n.hung || (st.exited && st.code == 255))) {
      wait_for_host(i, how, t - n.started_at, t);
      return true;
    }
    // A set-up that failed at the node's first start (a configuration error) fails again on every restart: said
    // once, no restart, and the launch stops (it would run on without the node, the graph not being the one that
    // was asked for). A node that ran before goes by its restart policy.
    if (st.exited && st.code == fploc::rt::kSetupFailedExitCode && !n.hung && n.restarts == 0) {
      fx_.log("node '" + n.policy.name + "' failed at set-up (" + how +
              ": a configuration error, see its 'setup failed' line): not restarted; stopping the launch");
      n.state = State::Dead;
      died_.push_back(n.policy.name);
      publish(i, "dead", "setup failed (" + how + ")");
      begin_shutdown(t);
      return true;
    }
    settle_exit(i, failed, how, t, t - n.started_at, t);
    return true;
  }
  return false;
}

void Supervisor::settle_exit(size_t i, bool failed, const std::string& how, double t_exit, double ran_s, double t) {
  auto& n = nodes_[i];
  const auto d = n.tracker.on_exit(t_exit, ran_s, failed);
  if (!d.restart && !d.give_up) {
    fx_.log("node '" + n.policy.name + "' " + how + (failed ? " (restart policy: not restarted)" : ""));
    n.state = failed ? State::Dead : State::Stopped;
    if (failed) died_.push_back(n.policy.name);
    publish(i, failed ? "dead" : "stopped", how);
  } else {
    apply_restart(i, d, (n.hung ? "hung, " : "") + how, t);
  }
}

void Supervisor::wait_for_host(size_t i, const std::string& how, double ran_s, double t) {
  auto& n = nodes_[i];
  auto& h = hosts_[n.policy.host];
  n.state = State::WaitingForHost;
  n.wait_since = t;
  n.wait_ran = ran_s;
  n.wait_why = how;
  n.host_confirmed = h.down;
  const std::string what = "node '" + n.policy.name + "' " + (n.hung ? "hung, " : "") + how;
  if (h.down) {
    fx_.log(what + ": host '" + n.policy.host + "' " + h.why + ": waiting for host '" + n.policy.host + "'");
  } else {
    fx_.log(what + ": checking whether host '" + n.policy.host + "' answers (if not, the node waits for it)");
    if (!h.probing) h.next_probe = t;
  }
  publish(i, "waiting", waiting_error(i));
  if (!h.probing && t >= h.next_probe) {
    h.probing = true;
    fx_.probe_host(n.policy.host);
  }
}

void Supervisor::on_host_probe(const std::string& host, bool reachable, const std::string& why, double t) {
  const auto it = hosts_.find(host);
  if (it == hosts_.end()) return;
  auto& h = it->second;
  h.probing = false;
  if (shutting_down_) return;
  std::vector<size_t> waiting;
  for (size_t i = 0; i < nodes_.size(); ++i)
    if (nodes_[i].state == State::WaitingForHost && nodes_[i].policy.host == host) waiting.push_back(i);
  if (reachable) {
    const bool was_down = h.down;
    const double away = t - h.down_since;
    h = HostWatch{};
    std::vector<size_t> back;
    for (size_t i : waiting) {
      auto& n = nodes_[i];
      if (n.host_confirmed) {
        back.push_back(i);
        continue;
      }
      // The host answered at once: the session's failure was the node's own, charged as any other.
      fx_.log("host '" + host + "' answers: node '" + n.policy.name + "' failed on its own");
      settle_exit(i, true, n.wait_why, n.wait_since, n.wait_ran, t);
    }
    if (was_down && !back.empty()) {
      std::string names;
      for (size_t i : back) names += (names.empty() ? "'" : ", '") + nodes_[i].policy.name + "'";
      fx_.log("host '" + host + "' answers again (away for " + fmt2(away) + " s): starting " + names);
    }
    for (size_t i : back) {
      auto& n = nodes_[i];
      if (n.ever_started) ++n.restarts;  // FPLOC_RESTARTS: a node that ran before is a restarted one
      start(i, t);
    }
    return;
  }
  if (!h.down) {
    h.down = true;
    h.down_since = t;
    for (size_t i : waiting) h.down_since = std::min(h.down_since, nodes_[i].wait_since);
    h.delay = 0;
  }
  const bool news = why != h.why;
  h.why = why;
  h.delay = h.delay > 0 ? std::min(h.delay * 2, cfg_.host_probe_max_s) : cfg_.host_probe_initial_s;
  h.next_probe = t + h.delay;
  for (size_t i : waiting)
    if (!nodes_[i].host_confirmed) {
      nodes_[i].host_confirmed = true;
      publish(i, "waiting", waiting_error(i));
    }
  if (news && !waiting.empty())
    fx_.log("host '" + host + "' " + why + ": " + nodes_waiting_on(host) + " waiting for host '" + host +
            "'; probing it again in " + fmt2(h.delay) + " s, then with backoff (at most every " +
            fmt2(cfg_.host_probe_max_s) + " s)");
}

void Supervisor::apply_restart(size_t i, const fploc::rt::RestartDecision& d, const std::string& why, double t) {
  auto& n = nodes_[i];
  if (!d.restart) {
    fx_.log("node '" + n.policy.name + "' " + why + ": " + std::to_string(d.max_restarts) + " restarts within " +
            fmt2(d.window_s) + " s already, giving up (dead)");
    n.state = State::Dead;
    died_.push_back(n.policy.name);
    publish(i, "dead", why + "; too many restarts");
    return;
  }
  ++n.restarts;
  n.next_start = t + d.delay;
  n.state = State::Backoff;
  fx_.log("node '" + n.policy.name + "' " + why + "; restarting in " + fmt2(d.delay) + " s (restart " +
          std::to_string(n.restarts) + ", " + std::to_string(d.in_window) + "/" + std::to_string(d.max_restarts) +
          " within " + fmt2(d.window_s) + " s)");
  publish(i, "restarting", why);
}

void Supervisor::request_stop(size_t i, double t) {
  begin_stop(i, false, t);
  publish(i, "stopping", "");
}

void Supervisor::request_restart(size_t i, double t) {
  auto& n = nodes_[i];
  n.tracker.reset();
  died_.erase(std::remove(died_.begin(), died_.end(), n.policy.name), died_.end());  // revived: no longer ended dead
  if (n.pid > 0) {
    begin_stop(i, true, t);
  } else {
    if (n.started_at > 0 || n.restarts > 0) ++n.restarts;
    start(i, t);
  }
}

void Supervisor::tick(double t) {
  if (shutting_down_) advance_shutdown(t);
  // Hosts that nodes wait for: probed with backoff (the answer comes through on_host_probe). A host nobody
  // waits for any more (its nodes stopped on request) is forgotten: a later failure probes it afresh.
  for (auto& [name, h] : hosts_) {
    if (shutting_down_ || h.probing) continue;
    const bool waited_for = std::any_of(nodes_.begin(), nodes_.end(), [&](const Run& n) {
      return n.state == State::WaitingForHost && n.policy.host == name;
    });
    if (!waited_for) {
      h = HostWatch{};
      continue;
    }
    if (t < h.next_probe) continue;
    h.probing = true;
    fx_.probe_host(name);
  }
  for (size_t i = 0; i < nodes_.size(); ++i) {
    auto& n = nodes_[i];
    if (n.state == State::Stopping) escalate(i, t);
    if (shutting_down_) continue;
    if (n.state == State::Backoff && t >= n.next_start) start(i, t);
    if (n.state == State::Running && n.policy.supervised) check_heartbeat(i, t);
  }
  if (t - last_report_ >= cfg_.report_period_s) {
    last_report_ = t;
    for (size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].state == State::Dead || nodes_[i].state == State::Backoff)
        publish(i, state_name(nodes_[i].state), "");
      else if (nodes_[i].state == State::WaitingForHost)
        publish(i, "waiting", waiting_error(i));
  }
}

std::optional<int> Supervisor::finished() {
  if (!shutting_down_ && std::all_of(nodes_.begin(), nodes_.end(), [](const Run& n) {
        return n.state == State::Stopped || n.state == State::Dead;
      })) {
    const bool dead = std::any_of(nodes_.begin(), nodes_.end(), [](const Run& n) { return n.state == State::Dead; });
    fx_.log(std::string("no node left running (") + (dead ? "some failed" : "all finished") + "): exiting");
    return dead ? 1 : 0;
  }
  if (shutting_down_ && std::all_of(nodes_.begin(), nodes_.end(), [](const Run& n) { return n.pid <= 0; })) {
    auto names = [](const std::vector<std::string>& v) {
      std::string s;
      for (const auto& n : v) s += (s.empty() ? "'" : ", '") + n + "'";
      return s;
    };
    std::string how;
    if (!died_.empty()) how += "; dead during the run: " + names(died_);
    if (!waiting_at_shutdown_.empty()) how += "; still waiting for their host: " + names(waiting_at_shutdown_);
    if (!killed_.empty()) how += "; killed: " + names(killed_);
    fx_.log("all nodes stopped" + how + (how.empty() ? "" : " (exit code 1)"));
    for (size_t i = 0; i < nodes_.size(); ++i) publish(i, "stopped", "");
    return how.empty() ? 0 : 1;
  }
  return std::nullopt;
}

}  // namespace fploc::launch
