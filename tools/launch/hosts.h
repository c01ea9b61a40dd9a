// Hosts of a graph (graph.proto Host): how `fploc launch` reaches a node's computer with OpenSSH and what
// it runs there. Paths map from this checkout to the host's: the graph and the build's bin/ keep their
// place relative to the fploc root (Host.fploc_root, default: the same path as here).
#pragma once
#include <string>
#include <vector>

#include "graph.pb.h"

namespace fploc::launch {

struct HostPlan {
  fploc::Host spec;
  std::string local_root;  // this checkout (parent of the build folder)
  std::string local_bin;   // this build's bin/
  std::string root() const;
  std::string bin() const;
  // A local path (graph, executable) as seen on the host.
  std::string map_path(const std::string& local_path) const;
  // ssh argv that runs `command` (a shell command line) on the host: no tty, no password prompts,
  // keep-alives so a cut link is noticed within ~3 s.
  std::vector<std::string> ssh_argv(const std::string& command, double connect_timeout_s = 3) const;
  // The launcher keeps one master connection per host (`ssh -M -N`) so that a node's (re)start is a new
  // session on it (milliseconds) instead of a new ssh handshake; sessions fall back to their own
  // connection while the master is down. "" = no multiplexing.
  std::string control_path;
  std::vector<std::string> master_argv() const;
  // The host probe (`--check`, the launch's check, and the launcher's probes of a host its nodes wait for): ssh
  // running `command` over a connection of its own (never a multiplexed one, which may outlive a cut link).
  std::vector<std::string> probe_argv(const std::string& command) const;
  // "not reachable with ssh (ADDRESS as USER): <ssh's first line>" for a probe that ended with `rc` (-1: timed out).
  std::string unreachable(int rc, const std::string& output) const;
};

std::string shell_quote(const std::string& s);
// "<bin>/fploc-remote --timeout S --restarts N -- <exe> <args...>" for one node on the host.
std::string remote_node_command(const HostPlan& h, const std::vector<std::string>& local_argv, int restarts,
                                double watchdog_s);
// The checkout's commit here ("" when not a git checkout).
std::string local_commit(const std::string& root);

// `fploc launch --check` for the hosts the graph's enabled nodes use: reachable with ssh (BatchMode), fploc
// present there (fploc-remote and every executable of its nodes in the host's bin/), at this checkout's
// commit, and multicast leaving through lcm_interface when the graph names one. One error per problem,
// naming the host.
struct HostProblem {
  std::string host, message;
  bool unreachable = false;  // ssh did not get there (nothing else about the host could be checked)
};
std::vector<HostProblem> check_hosts(const fploc::Graph& g, const std::vector<HostPlan>& hosts,
                                     const std::vector<std::pair<std::string, std::string>>& host_exe,  // host, exe path
                                     const std::string& lcm_url);

// Runs argv with stdout+stderr captured; exit code (-1 on timeout/failure).
int run_merged(const std::vector<std::string>& argv, double timeout_s, std::string& out);

}  // namespace fploc::launch
