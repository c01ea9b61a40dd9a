// Restart bookkeeping of the launcher (graph.proto RestartPolicy): mode, max restarts within a window,
// exponential backoff. Pure logic (times are passed in), unit-tested.
#pragma once
#include <deque>

#include "graph.pb.h"

namespace fploc::rt {

// A node whose setup() failed (its options, plan, files: "[NAME] setup failed: ..." on stderr and a "dead"
// heartbeat) exits with this code (sysexits' EX_CONFIG). `fploc launch` does not restart it: the same
// set-up would fail again. It says so once and stops the launch (docs/notes/launch-check.md).
// Only at a node's first start: a node that ran and then fails at set-up on a restart goes by the restart policy.
// A set-up failure that may pass (a socket not open yet at boot) throws SetupMayPass: exit 1, restarted as a crash.
constexpr int kSetupFailedExitCode = 78;

struct RestartDecision {
  bool restart = false;   // start again after `delay`
  bool give_up = false;   // restart wanted but the window is full: the node is dead
  double delay = 0;
  int in_window = 0;      // restarts within the window, this one included
  int max_restarts = 0;
  double window_s = 0;
};

class RestartTracker {
 public:
  explicit RestartTracker(const fploc::RestartPolicy& p = {});
  // The process exited at time t after running ran_s; failed = non-zero exit, a signal or a hang.
  RestartDecision on_exit(double t, double ran_s, bool failed);
  // A control request restarted the node on purpose: fresh window and backoff.
  void reset();
  double window_s() const { return window_; }

 private:
  fploc::RestartPolicy::Mode mode_;
  int max_;
  double window_, initial_, max_backoff_, factor_, backoff_;
  std::deque<double> times_;
};

}  // namespace fploc::rt
