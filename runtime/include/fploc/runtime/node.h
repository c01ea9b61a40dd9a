// The one runtime every fploc process uses. A node is a small class that wires a transport-free
// library to typed ports; the runtime does options, LCM, telemetry, timers and shutdown.
//
//   class SegmenterNode : public fploc::rt::Node {
//    public:
//     static fploc::rt::NodeSpec spec() {
//       return {"segmenter", "segmenter", "ceiling/ground planes -> roll, pitch, z; wall points",
//               {fploc::rt::input<fploc::scan_t>("scan", "OS1_SCAN"),
//                fploc::rt::output<fploc::segments_t>("segments", "FPLOC_SEGMENTS")}};
//     }
//     void setup(fploc::rt::Context& ctx) override {
//       const auto& opt = ctx.options<fploc::SegmenterOptions>();
//       out_ = ctx.advertise<fploc::segments_t>("segments");
//       ctx.subscribe<fploc::scan_t>("scan", [this](const fploc::scan_t& m) { ... out_.publish(seg); });
//     }
//    private:
//     fploc::rt::Publisher<fploc::segments_t> out_;
//   };
//   FPLOC_REGISTER_NODE(SegmenterNode)
//
// Build with fploc_add_node(segmenter SOURCES segmenter_node.cpp DEPS fploc_segmentation): that gives
// the executable fploc-segmenter (standalone or under `fploc launch`) and lets `fploc replay` compose it.
#pragma once
#include <google/protobuf/message.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "fploc/runtime/telemetry.h"

namespace fploc::rt {

// What a live node that falls behind does with the messages queued on an input (graph: Port.queue).
// kLatest: the runtime reads everything queued first, then calls the handler once with the newest
// message of the port; the older ones are dropped and counted in telemetry as the port's drops. Composed
// replay (`fploc replay`) ignores it and delivers every message.
enum class Queue { kAll, kLatest };

struct PortSpec {
  std::string name;
  std::string lcm_type;          // e.g. "fploc.scan_t"
  std::string default_channel;   // used when the graph does not map the port ("" = not connected)
  bool output = false;
  Queue queue = Queue::kAll;     // inputs: the node's default (the graph's Port.queue overrides it)
};

struct NodeSpec {
  std::string type;              // registry key; the executable is fploc-<type>
  std::string options_field;     // field of Node.options in graph.proto ("" = takes no options)
  std::string description;
  std::vector<PortSpec> ports;
};

template <class Msg>
PortSpec input(std::string name, std::string default_channel, Queue queue = Queue::kAll) {
  return {std::move(name), std::string("fploc.") + Msg::getTypeName(), std::move(default_channel), false, queue};
}
template <class Msg>
PortSpec output(std::string name, std::string default_channel) {
  return {std::move(name), std::string("fploc.") + Msg::getTypeName(), std::move(default_channel), true};
}

class Context;

class Node {
 public:
  virtual ~Node() = default;
  virtual void setup(Context& ctx) = 0;
  // Called once before the process exits (after the last message); flush files here.
  virtual void shutdown() {}
};

// A typed output port. Cheap to copy; publishing counts messages for telemetry.
template <class Msg>
class Publisher {
 public:
  Publisher() = default;
  void publish(const Msg& m) const;
  bool valid() const { return ctx_ != nullptr; }
  const std::string& channel() const { return channel_; }

 private:
  friend class Context;
  Context* ctx_ = nullptr;
  std::string channel_;
  PortCounters* counters_ = nullptr;
};

class Bus;  // LCM instance shared by all nodes of a process

// Thrown from Node::setup() for a failure that may pass by itself (a UDP port still held, an interface without
// its address yet at boot): the process exits 1 and the launcher restarts it by the node's restart policy. Any
// other exception from setup() is a configuration error (exit kSetupFailedExitCode, restart.h).
struct SetupMayPass : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Context {
 public:
  Context(Bus& bus, const NodeSpec& spec, std::string instance_name,
          std::unique_ptr<google::protobuf::Message> options, std::vector<std::pair<std::string, std::string>> port_map,
          std::string base_dir, bool composed);
  ~Context();

  const std::string& name() const { return name_; }
  const NodeSpec& spec() const { return spec_; }
  // The node's typed options from the graph (default values when the graph gives none).
  template <class Opt>
  const Opt& options() const {
    static const Opt kDefault;
    const auto* o = dynamic_cast<const Opt*>(options_.get());
    return o ? *o : kDefault;
  }
  // Resolves a path from the options: absolute, or relative to the graph file's folder.
  std::string resolve_path(const std::string& p) const;
  // True inside `fploc replay` (one process, lock-step): no wall-clock timers or sockets.
  bool composed() const { return composed_; }
  // How often the launcher has started this node before (FPLOC_RESTARTS; 0 on the first start and in
  // composed mode). A restarted node may not want the graph's start-of-run state (e.g. an initial pose).
  int restarts() const { return restarts_; }
  void set_restarts(int n) { restarts_ = n; }
  // The graph's robot (Graph.robot, "" = none). Every port channel already carries it; `ns` applies it
  // to channels a node uses directly (FPLOC_CONTROL, ...).
  const std::string& robot() const { return robot_; }
  void set_robot(const std::string& r);
  std::string ns(const std::string& channel) const;
  const std::string& channel(const std::string& port) const;
  // The queue policy of an input: the graph's Port.queue (set_queue_overrides), else the spec's.
  Queue queue(const std::string& port) const;
  void set_queue_overrides(std::vector<std::pair<std::string, Queue>> q) { queue_overrides_ = std::move(q); }

  template <class Msg>
  Publisher<Msg> advertise(const std::string& port);
  template <class Msg>
  void subscribe(const std::string& port, std::function<void(const Msg&)> fn);

  // Periodic work (drivers, simulator); not allowed in composed mode.
  void every(double period_s, std::function<void()> fn);
  // Calls fn whenever fd is readable (sockets).
  void watch_fd(int fd, std::function<void()> fn);
  // Records an error for telemetry (last_error, count) and prints it to stderr the first few times (then
  // every 1000th); returns whether it printed this one.
  bool error(const std::string& msg);
  // The condition behind the last error is over (e.g. the metadata file appeared): telemetry's last_error
  // is cleared, the error count stays.
  void error_resolved() { stats_.last_error.clear(); }
  // A condition that keeps the node from doing its job while it lasts (the dashboard cannot listen on its port):
  // reported once as an error (stderr, count), and every heartbeat meanwhile has state "failing" with it as
  // last_error. "" ends it: heartbeats say "running" again, without that last_error.
  void set_failing(const std::string& what);
  // The node's own state line in telemetry (node_status_t.detail, shown on the dashboard), e.g. a
  // sensor's status and active alerts; unlike last_error it stays until replaced ("" clears it).
  void set_detail(const std::string& text) { stats_.detail = text; }
  // A change of the node's own status (a fit going OK -> POOR -> LOST, ...) with its reason, said in one way by
  // every node: on stderr as "[name] LINE" for the first kStatusChangesPrinted changes (the last of them adds that
  // further changes are only in telemetry), and LINE becomes telemetry's detail (`keep_detail` false: the detail
  // is cleared instead, the new status needs no explanation, e.g. OK). `print` false: the change was already said
  // on stderr (an error() that printed); it is neither printed nor counted. Returns whether it printed.
  static constexpr int kStatusChangesPrinted = 200;
  bool status_changed(const std::string& line, bool keep_detail = true, bool print = true);
  // Asks the process to stop after the current message (e.g. a pcap source reached its end).
  void request_stop();

  // Internal (used by the runtime).
  NodeStats& stats() { return stats_; }
  void publish_raw(const std::string& channel, const void* data, int size, PortCounters* c);
  Bus& bus() { return bus_; }

 private:
  void subscribe_raw(const std::string& port, std::function<bool(const void*, int)> fn);
  void warn_yaw_units(const google::protobuf::Message& m, const std::string& path) const;
  Bus& bus_;
  NodeSpec spec_;
  std::string name_;
  std::unique_ptr<google::protobuf::Message> options_;
  std::vector<std::pair<std::string, std::string>> port_map_;
  std::string base_dir_;
  bool composed_;
  int restarts_ = 0;
  int status_changes_ = 0;  // status_changed() lines printed
  std::string robot_;
  std::vector<std::pair<std::string, Queue>> queue_overrides_;
  NodeStats stats_;
};

// ---- registry -------------------------------------------------------------------------------
using NodeFactory = std::function<std::unique_ptr<Node>()>;
struct Registration {
  NodeSpec spec;
  NodeFactory make;
};
std::vector<Registration>& registry();
const Registration* find_registration(const std::string& type);
// `fploc-segmenter` -> "segmenter".
std::string type_from_executable(const std::string& executable);

template <class N>
struct Registrar {
  Registrar() { registry().push_back({N::spec(), [] { return std::unique_ptr<Node>(new N()); }}); }
};

#define FPLOC_CONCAT_(a, b) a##b
#define FPLOC_CONCAT(a, b) FPLOC_CONCAT_(a, b)
#define FPLOC_REGISTER_NODE(Class) static ::fploc::rt::Registrar<Class> FPLOC_CONCAT(fploc_registrar_, __LINE__);

// Entry point of every node executable (runtime/src/node_main.cpp calls it).
int node_main(int argc, char** argv);
// The live loop's LCM step (used by node_main; public for tests): handles what LCM has queued (for at
// most ~max_s, at least one message), then calls each keep-latest input's handler with its newest
// message. Returns the number of handler calls.
int dispatch_live(Bus& bus, double max_s = 0.1);
// Calls the keep-latest handlers that hold a message (dispatch_live's second half; also at shutdown).
int run_latest();

// ---- template implementation ----------------------------------------------------------------
template <class Msg>
void Publisher<Msg>::publish(const Msg& m) const {
  if (!ctx_) return;
  const int n = m.getEncodedSize();
  thread_local std::vector<uint8_t> buf;
  buf.resize(size_t(n));
  m.encode(buf.data(), 0, n);
  ctx_->publish_raw(channel_, buf.data(), n, counters_);
}

template <class Msg>
Publisher<Msg> Context::advertise(const std::string& port) {
  Publisher<Msg> p;
  p.ctx_ = this;
  p.channel_ = channel(port);
  p.counters_ = &stats_.port(port, p.channel_, true);
  return p;
}

template <class Msg>
void Context::subscribe(const std::string& port, std::function<void(const Msg&)> fn) {
  if (channel(port).empty()) return;  // port mapped to "" (or no default channel): not connected
  auto* counters = &stats_.port(port, channel(port), false);
  subscribe_raw(port, [fn = std::move(fn), counters](const void* data, int size) {
    Msg m;
    if (m.decode(data, 0, size) < 0) return false;
    if constexpr (requires { m.seq; }) counters->observe_seq(m.seq);
    fn(m);
    return true;
  });
}

}  // namespace fploc::rt
