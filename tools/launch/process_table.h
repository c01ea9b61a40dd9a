// The launcher's process table: what runs for each node of the graph (executable, arguments,
// overrides) and the OS side of running it — fork/exec into its own process group with
// PR_SET_PDEATHSIG=SIGKILL, signals to the group, reaping. No policy here (supervisor.h decides).
#pragma once
#include <sys/types.h>

#include <string>
#include <vector>

#include "fploc/runtime/node.h"
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
};

class ProcessTable {
 public:
  ProcessTable(std::vector<ProcessEntry> entries, std::string graph_abs) : entries_(std::move(entries)), graph_(std::move(graph_abs)) {}
  size_t size() const { return entries_.size(); }
  ProcessEntry& operator[](size_t i) { return entries_[i]; }
  const ProcessEntry& operator[](size_t i) const { return entries_[i]; }

  // The command line of entry i: EXE --graph GRAPH --node NAME [--set k=v ...] [args...] (fploc nodes).
  std::vector<std::string> command(size_t i) const;
  // Starts entry i in its own process group with FPLOC_RESTARTS=restarts; -1 (and `error`) on failure.
  pid_t spawn(size_t i, int restarts, std::string& error) const;
  static void signal_group(pid_t pid, int sig);
  // Reaps one exited child without blocking: its pid (> 0) and status, or 0 when none.
  static pid_t reap_one(ExitStatus& st);

 private:
  std::vector<ProcessEntry> entries_;
  std::string graph_;
};

}  // namespace fploc::launch
