// The launcher's process table: what runs for each node of the graph (executable, arguments,
// overrides) and the OS side of running it — fork/exec into its own process group with
// PR_SET_PDEATHSIG=SIGKILL, signals to the group, reaping. No policy here (supervisor.h decides).
#pragma once
#include <sys/types.h>

#include <string>
#include <vector>

#include <memory>

#include "fploc/runtime/node.h"
#include "hosts.h"
#include "supervisor.h"

namespace fploc::launch {

struct ProcessEntry {
  std::string name;
  std::string exe_name;               // as in the graph (or the control request)
  std::string exe_path;               // resolved
  bool fploc_node = false;            // speaks the runtime protocol (--graph/--node, telemetry)
  std::string options_field;          // declared by the executable
  fploc::rt::NodeSpec spec;           // its --describe (fploc nodes)
  std::vector<std::string> sets;      // overrides (launch --set, then control requests), field=value
  std::vector<std::string> args;      // extra arguments from the graph
  std::shared_ptr<const HostPlan> host;  // null: runs here; else through ssh with fploc-remote there
};

// A remote node's ssh session: the launcher writes one-byte commands ('.', 'I', 'T', 'K') to `in` and
// reads the node's output (ssh's stdout and stderr) from `out`.
struct RemoteIo {
  int in = -1, out = -1;
  std::string partial;     // output not yet ended by a newline
  pid_t remote_pid = -1;   // the node's pid on its host (first line from fploc-remote)
};

class ProcessTable {
 public:
  ProcessTable(std::vector<ProcessEntry> entries, std::string graph_abs)
      : entries_(std::move(entries)), graph_(std::move(graph_abs)), io_(entries_.size()) {}
  ~ProcessTable();
  size_t size() const { return entries_.size(); }
  ProcessEntry& operator[](size_t i) { return entries_[i]; }
  const ProcessEntry& operator[](size_t i) const { return entries_[i]; }

  // The command line of entry i: EXE --graph GRAPH --node NAME [--set k=v ...] [args...] (fploc nodes).
  std::vector<std::string> command(size_t i) const;
  // Starts entry i in its own process group with FPLOC_RESTARTS=restarts; -1 (and `error`) on failure.
  // Remote entries: `ssh HOST fploc-remote -- <the same command, paths mapped>` with pipes in io(i).
  pid_t spawn(size_t i, int restarts, std::string& error);
  bool remote(size_t i) const { return entries_[i].host != nullptr; }
  RemoteIo& io(size_t i) { return io_[i]; }
  // Sends a one-byte command to a remote node's fploc-remote (ignored when the session is gone).
  void send(size_t i, char c);
  // Complete output lines of a remote node (non-blocking; learns its remote pid). `eof` when ssh closed it.
  std::vector<std::string> read_lines(size_t i, bool& eof);
  void close_io(size_t i);
  double watchdog_s = 3.0;  // fploc-remote stops its node after this long without a byte from us
  static void signal_group(pid_t pid, int sig);
  // Reaps one exited child without blocking: its pid (> 0) and status, or 0 when none.
  static pid_t reap_one(ExitStatus& st);

 private:
  std::vector<ProcessEntry> entries_;
  std::string graph_;
  std::vector<RemoteIo> io_;
};

}  // namespace fploc::launch
