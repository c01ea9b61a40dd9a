// The launcher's control channel: a node_command_t from `fploc node restart|stop|start` or the
// dashboard, checked (token, node name, a swapped-in executable must take the graph's options and offer
// the same ports with the same LCM types, overrides must name existing fields) before anything stops.
// The result is a decision; the launcher applies it to the process table and the supervisor.
#pragma once
#include <fploc/node_command_t.hpp>

#include <string>

#include "fploc/runtime/graph.h"
#include "fploc/runtime/validate.h"
#include "process_table.h"

namespace fploc::launch {

struct ControlDecision {
  enum Kind { Reject, Stop, Restart } kind = Reject;
  std::string node;
  std::string error;     // Reject: why
  ProcessEntry entry;    // Restart: what to run from now on (executable, overrides)
};

// `entry` is the node's current process table entry (nullptr: no node of that name).
ControlDecision decide_control(const fploc::node_command_t& m, const ProcessEntry* entry, const fploc::Graph& graph,
                               const fploc::rt::ValidateHooks& hooks);

}  // namespace fploc::launch
