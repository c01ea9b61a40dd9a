// Telemetry statistics kept by the runtime for each node (no LCM here; unit-tested on its own).
#pragma once
#include <algorithm>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace fploc::rt {

// Exact percentiles of the samples since the last reset.
class LatencyWindow {
 public:
  void add(double ms) { samples_.push_back(ms); }
  // q in [0, 1]; nearest-rank percentile; 0 when empty.
  double percentile(double q) const;
  size_t size() const { return samples_.size(); }
  void reset() { samples_.clear(); }
  double sum() const;

 private:
  std::vector<double> samples_;
};

// Message rate over a sliding window, from the arrivals in it: (n - 1) / (newest - oldest). Counting the
// arrivals of the last period instead jumps with bursts: the window optimizer releases the poses of
// non-keyframes together with the next keyframe (3-4 poses every 0.3 s at 10 Hz), which a 1-2 s count
// read as 7-13 Hz. A stream idle for over 1.5 s reads lower as the idle time grows, 0 once it left the window.
class RateMeter {
 public:
  RateMeter() = default;
  explicit RateMeter(double window_s) : window_s_(window_s) {}
  void add(double t_s);
  double rate_hz(double now_s);

 private:
  void forget_before(double t_s);
  double window_s_ = 5.0;
  std::deque<double> times_;
};

struct PortCounters {
  std::string port, channel;
  bool output = false;
  int64_t messages = 0;        // since start
  int64_t period_messages = 0; // since the last heartbeat
  RateMeter rate;              // messages per second (node_status_t port rate_hz)
  int64_t dropped = 0;
  int64_t undecodable = 0;
  int64_t last_seq = -1;
  LatencyWindow latency;       // inputs: this port's handler latency this period
  // Messages a keep-latest input skipped since its last delivery (already in `dropped`): the gap they
  // leave in the sequence is not counted again.
  int64_t superseded = 0;
  // Sequence gaps on an input are counted as drops; a restart of the publisher (seq going back) is not.
  void observe_seq(int64_t seq) {
    if (last_seq >= 0 && seq > last_seq + 1) dropped += std::max<int64_t>(0, seq - last_seq - 1 - superseded);
    superseded = 0;
    last_seq = seq;
  }
};

// CPU time of this process as a percentage of one core between two calls.
class CpuMeter {
 public:
  CpuMeter();
  double sample_percent();

 private:
  double last_cpu_s_, last_wall_s_;
};

struct NodeStats {
  std::deque<PortCounters> ports;  // deque: stable addresses for publishers/subscribers
  LatencyWindow latency;           // handler latency this period
  LatencyWindow latency_total;     // every handler call, composed replay only (its --json breakdown)
  double cpu_s_total = 0;          // thread CPU time in handlers, composed replay only (the machine may be shared)
  int64_t errors = 0;
  std::string last_error;
  std::string detail;              // Context::set_detail (node_status_t.detail)
  std::string failing;             // Context::set_failing: while set, heartbeats say state "failing"
  double busy_s_period = 0;        // time spent in handlers this period

  PortCounters& port(const std::string& name, const std::string& channel, bool output);
  int64_t messages(bool output) const;
  int64_t dropped() const;
  int64_t undecodable() const;
  void end_period();               // resets per-period counters
};

}  // namespace fploc::rt
