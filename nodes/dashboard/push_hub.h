// The dashboard's push hub: the latest value of every event stream ("pose", "nodes", ...) as
// ready-to-send JSON, and what of it is due for the one broadcaster that feeds every SSE client.
// Latest-value semantics: a stream updated three times between two pushes sends its newest value once;
// nothing is queued. Each stream goes out at most max_hz times per second, immediately when allowed.
// Thread-safe (one mutex, held only to copy strings); no LCM, no sockets.
#pragma once
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>

namespace fploc::dashboard {

class PushHub {
 public:
  // Called (outside the lock) after every update, e.g. to wake the broadcaster.
  void set_notify(std::function<void()> f);
  void set(const std::string& stream, std::string json);
  std::string get(const std::string& stream) const;  // "" = never set
  // {"stream": value, ...} of every stream (GET /api/state).
  std::string state_json() const;
  // Everything, as SSE events (a new client's first message).
  std::string snapshot() const;
  // The SSE text of the streams whose newest value has not been pushed yet and whose rate cap allows a
  // push at now_s; `next_due_s` is when a held-back stream may go (infinity when none waits).
  std::string take_due(double now_s, double max_hz, double& next_due_s);
  uint64_t pushes() const;

 private:
  struct Slot {
    uint64_t version = 0, pushed = 0;
    double last_push_s = -std::numeric_limits<double>::infinity();
    std::string json;
  };
  mutable std::mutex mu_;
  std::map<std::string, Slot> slots_;
  uint64_t version_ = 0, pushes_ = 0;
  std::function<void()> notify_;
};

// "event: NAME\ndata: JSON\n\n"
std::string sse_event(const std::string& name, const std::string& json);

}  // namespace fploc::dashboard
