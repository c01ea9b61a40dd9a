#include "fploc/runtime/telemetry.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

namespace fploc::rt {

double LatencyWindow::percentile(double q) const {
  if (samples_.empty()) return 0.0;
  std::vector<double> s = samples_;
  const size_t rank = size_t(std::ceil(std::clamp(q, 0.0, 1.0) * double(s.size())));
  const size_t k = rank == 0 ? 0 : rank - 1;
  std::nth_element(s.begin(), s.begin() + long(k), s.end());
  return s[k];
}

double LatencyWindow::sum() const { return std::accumulate(samples_.begin(), samples_.end(), 0.0); }

static double process_cpu_s() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}
static double wall_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

CpuMeter::CpuMeter() : last_cpu_s_(process_cpu_s()), last_wall_s_(wall_s()) {}

double CpuMeter::sample_percent() {
  const double c = process_cpu_s(), w = wall_s();
  const double dc = c - last_cpu_s_, dw = w - last_wall_s_;
  last_cpu_s_ = c;
  last_wall_s_ = w;
  return dw > 0 ? 100.0 * dc / dw : 0.0;
}

void RateMeter::forget_before(double t_s) {
  while (!times_.empty() && times_.front() < t_s) times_.pop_front();
}

void RateMeter::add(double t_s) {
  times_.push_back(t_s);
  forget_before(t_s - window_s_);
}

double RateMeter::rate_hz(double now_s) {
  forget_before(now_s - window_s_);
  if (times_.size() < 2) return 0.0;
  const double n = double(times_.size() - 1);
  // At least 1 s (or the whole window if shorter): the first burst of a stream is not a rate.
  double span = std::max(times_.back() - times_.front(), std::min(window_s_, 1.0));
  // Idle for longer than five mean intervals and 1.5 s (a standing robot's final poses come once a second,
  // with its keyframes): the stream stalled; count the idle time.
  if (now_s - times_.back() > std::max(1.5, 5.0 * span / n)) span = now_s - times_.front();
  return span > 0 ? n / span : 0.0;
}

PortCounters& NodeStats::port(const std::string& name, const std::string& channel, bool output) {
  for (auto& p : ports)
    if (p.port == name && p.output == output) return p;
  ports.push_back({});
  ports.back().port = name;
  ports.back().channel = channel;
  ports.back().output = output;
  return ports.back();
}

int64_t NodeStats::messages(bool output) const {
  int64_t n = 0;
  for (const auto& p : ports)
    if (p.output == output) n += p.messages;
  return n;
}
int64_t NodeStats::dropped() const {
  int64_t n = 0;
  for (const auto& p : ports) n += p.dropped;
  return n;
}
int64_t NodeStats::undecodable() const {
  int64_t n = 0;
  for (const auto& p : ports) n += p.undecodable;
  return n;
}
void NodeStats::end_period() {
  for (auto& p : ports) {
    p.period_messages = 0;
    p.latency.reset();
  }
  latency.reset();
  busy_s_period = 0;
}

}  // namespace fploc::rt
