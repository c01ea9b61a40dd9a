#include "fploc/runtime/restart.h"

#include <algorithm>

namespace fploc::rt {

static double or_default(double v, double d) { return v > 0 ? v : d; }

RestartTracker::RestartTracker(const fploc::RestartPolicy& p)
    : mode_(p.mode()),
      max_(p.max_restarts() > 0 ? p.max_restarts() : 5),
      window_(or_default(p.window_s(), 60.0)),
      initial_(or_default(p.backoff_initial_s(), 0.1)),
      max_backoff_(or_default(p.backoff_max_s(), 5.0)),
      factor_(or_default(p.backoff_factor(), 2.0)),
      backoff_(initial_) {}

void RestartTracker::reset() {
  times_.clear();
  backoff_ = initial_;
}

RestartDecision RestartTracker::on_exit(double t, double ran_s, bool failed) {
  RestartDecision d;
  d.max_restarts = max_;
  d.window_s = window_;
  const bool wanted = mode_ == fploc::RestartPolicy::ALWAYS || (mode_ == fploc::RestartPolicy::ON_FAILURE && failed);
  if (!wanted) return d;
  while (!times_.empty() && t - times_.front() > window_) times_.pop_front();
  if (int(times_.size()) >= max_) {
    d.give_up = true;
    d.in_window = int(times_.size());
    return d;
  }
  // Backoff grows with consecutive quick failures and resets after a run longer than the window.
  if (ran_s > window_) backoff_ = initial_;
  d.restart = true;
  d.delay = backoff_;
  backoff_ = std::min(backoff_ * factor_, max_backoff_);
  times_.push_back(t);
  d.in_window = int(times_.size());
  return d;
}

}  // namespace fploc::rt
