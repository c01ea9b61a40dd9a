// Running a short-lived program and reading what it prints (`fploc-x --describe`, `git rev-parse`,
// `ssh host ...`): stdin from /dev/null, a deadline after which the program (and its process group) is
// killed. No shell is involved.
#pragma once

#include <string>
#include <vector>

namespace fploc::rt {

struct RunOptions {
  double timeout_s = 10;
  bool merge_stderr = false;  // stderr into the captured output (else discarded)
  bool search_path = false;   // argv[0] looked up in PATH (execvp) instead of taken as a file name
};

struct RunResult {
  int exit_code = -1;     // -1 when it could not start, timed out or died of a signal
  bool timed_out = false;
  std::string output;     // what it printed (stdout, + stderr with merge_stderr)
  std::string problem;    // "" when it exited 0; else "exit code 3", "timed out", "killed by signal 9", ...
};

RunResult run_program(const std::vector<std::string>& argv, const RunOptions& options = {});

}  // namespace fploc::rt
