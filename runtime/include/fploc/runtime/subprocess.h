// Child processes, without a shell:
// - run_program: a short-lived program whose output we read (`fploc-x --describe`, `git rev-parse`,
//   `ssh host ...`): stdin from /dev/null, a deadline after which the program (and its group) is killed.
// - spawn_supervised: a long-lived child that a supervisor watches (the launcher's nodes and ssh
//   masters, fploc-remote's node): its own process group, killed with its parent.
#pragma once

#include <sys/types.h>

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

struct SpawnOptions {
  static constexpr int kInherit = -1;
  static constexpr int kDevNull = -2;
  bool search_path = false;              // argv[0] looked up in PATH (execvp)
  const std::vector<std::string>* env = nullptr;  // "K=V" entries; nullptr: this process's environment
  int stdin_fd = kInherit;               // or kDevNull, or a descriptor to dup2 onto 0
  int stdout_fd = kInherit;              // a descriptor to dup2 onto 1
  int stderr_fd = kInherit;              // a descriptor to dup2 onto 2
  bool close_other_fds = false;          // close every descriptor >= 3 before exec
  std::string who;                       // prefix of the "cannot run" line written to stderr on exec failure
};

// fork + exec: the child gets its own process group (set on both sides of the fork, so kill(-pid) has no
// race), SIGKILL when this process dies (PR_SET_PDEATHSIG; it exits at once if this process already
// died), an empty signal mask and default handlers. Returns the pid, or -1 with `error` set.
pid_t spawn_supervised(const std::vector<std::string>& argv, const SpawnOptions& options, std::string& error);

}  // namespace fploc::rt
