// Whole-graph validation before anything starts (`fploc launch --check`, `fploc replay`): every problem
// is collected as `file:line: message`.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "fploc/runtime/graph.h"
#include "fploc/runtime/node.h"

namespace fploc::rt {

// The spec a node executable prints with `--describe` (JSON), and its parser.
std::string spec_json(const NodeSpec& spec);
// Throws std::runtime_error when the text is not a node description.
NodeSpec parse_spec_json(const std::string& json);

// Finds an executable: a path with '/' is taken as is (relative to the working directory); otherwise the
// build's bin folder `bin_dir` first, then PATH. Returns "" when not found or not executable.
std::string resolve_executable(const std::string& exe, const std::string& bin_dir);
// Folder of the running program (/proc/self/exe), i.e. the build's bin/ for fploc tools.
std::string self_bin_dir();

struct DescribeResult {
  bool describable = false;  // false: a foreign program (not fploc-*), its ports come from the graph only
  NodeSpec spec;
  std::string error;         // non-empty: an fploc executable failed to describe itself
};
// Runs `EXE --describe` (with a timeout) for fploc-* executables.
DescribeResult describe_executable(const std::string& resolved_path);

struct ValidateHooks {
  std::function<std::string(const std::string& exe)> resolve;           // "" = not found
  std::function<DescribeResult(const std::string& resolved)> describe;
};
// Hooks that look in `bin_dir` then PATH and run --describe (results cached per executable).
ValidateHooks default_hooks(const std::string& bin_dir);

struct ResolvedNode {
  int index = -1;            // in graph.node
  std::string executable;    // resolved path ("" when disabled and not found)
  DescribeResult desc;
};

// Checks: parse errors are the caller's; here names (empty, duplicate), executables (missing, failing
// --describe), the options field against what the executable declares, port names, restart policies,
// inputs with no producer and producer/consumer LCM type mismatches per channel. A disabled node is not
// started but its outputs still count as producers (it stands for a source outside the launch, e.g.
// lcm-logplayer). FPLOC_TELEMETRY, FPLOC_CONTROL and FPLOC_INITIAL_POSE are produced by the runtime /
// `fploc node` / `fploc node initial-pose`.
// "No producer" is not reported while an executable is missing (its outputs are unknown).
// A port mapped to channel "" (or whose default channel is "") is not connected.
bool validate_graph(const LoadedGraph& g, const ValidateHooks& hooks, std::vector<GraphError>& errors,
                    std::vector<ResolvedNode>* resolved = nullptr);

}  // namespace fploc::rt
