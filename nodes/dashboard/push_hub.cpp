#include "push_hub.h"

#include <algorithm>

namespace fploc::dashboard {

std::string sse_event(const std::string& name, const std::string& json) {
  return "event: " + name + "\ndata: " + json + "\n\n";
}

void PushHub::set_notify(std::function<void()> f) {
  std::lock_guard<std::mutex> lk(mu_);
  notify_ = std::move(f);
}

void PushHub::set(const std::string& stream, std::string json) {
  std::function<void()> n;
  {
    std::lock_guard<std::mutex> lk(mu_);
    auto& s = slots_[stream];
    s.json = std::move(json);
    s.version = ++version_;
    n = notify_;
  }
  if (n) n();
}

std::string PushHub::get(const std::string& stream) const {
  std::lock_guard<std::mutex> lk(mu_);
  auto it = slots_.find(stream);
  return it == slots_.end() ? std::string() : it->second.json;
}

std::string PushHub::state_json() const {
  std::lock_guard<std::mutex> lk(mu_);
  std::string out = "{";
  bool first = true;
  for (const auto& [name, s] : slots_) {
    out += (first ? "\"" : ",\"") + name + "\":" + s.json;
    first = false;
  }
  return out + "}";
}

std::string PushHub::snapshot() const {
  std::lock_guard<std::mutex> lk(mu_);
  std::string out;
  for (const auto& [name, s] : slots_) out += sse_event(name, s.json);
  return out;
}

std::string PushHub::take_due(double now_s, double max_hz, double& next_due_s) {
  const double period = max_hz > 0 ? 1.0 / max_hz : 0.0;
  next_due_s = std::numeric_limits<double>::infinity();
  std::lock_guard<std::mutex> lk(mu_);
  std::string out;
  for (auto& [name, s] : slots_) {
    if (s.version <= s.pushed) continue;
    if (s.last_push_s + period <= now_s) {
      out += sse_event(name, s.json);
      s.pushed = s.version;
      s.last_push_s = now_s;
    } else {
      next_due_s = std::min(next_due_s, s.last_push_s + period);
    }
  }
  if (!out.empty()) ++pushes_;
  return out;
}

uint64_t PushHub::pushes() const {
  std::lock_guard<std::mutex> lk(mu_);
  return pushes_;
}

}  // namespace fploc::dashboard
