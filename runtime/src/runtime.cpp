#include <fploc/node_command_t.hpp>
#include <fploc/node_status_t.hpp>
#include <poll.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "fploc/runtime/bus.h"
#include "fploc/runtime/robot.h"
#include "fploc/runtime/compose.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/node.h"
#include "fploc/runtime/restart.h"
#include "fploc/runtime/validate.h"

namespace fploc::rt {

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

Bus::Bus(const std::string& url) : url_(url.empty() ? kDefaultLcmUrl : url) {
  lcm_ = std::make_unique<lcm::LCM>(url_);
  if (!lcm_->good()) throw std::runtime_error("cannot open LCM provider '" + url_ + "'");
}

// ---- registry ---------------------------------------------------------------------------------
std::vector<Registration>& registry() {
  static std::vector<Registration> r;
  return r;
}
const Registration* find_registration(const std::string& type) {
  for (const auto& r : registry())
    if (r.spec.type == type) return &r;
  return nullptr;
}
std::string type_from_executable(const std::string& executable) {
  std::string base = std::filesystem::path(executable).filename().string();
  if (base.rfind("fploc-", 0) == 0) base = base.substr(6);
  std::replace(base.begin(), base.end(), '-', '_');
  return base;
}

// ---- context ----------------------------------------------------------------------------------
struct TimerEntry {
  double period, next;
  std::function<void()> fn;
};
struct FdEntry {
  int fd;
  std::function<void()> fn;
};
struct HandlerEntry {
  Context* ctx;
  PortCounters* counters;
  std::function<bool(const void*, int)> fn;
  bool latest = false;               // live keep-latest input: LCM's handler only keeps the newest here
  bool has_pending = false;
  std::vector<uint8_t> pending;
};

// Per-process loop state that nodes register timers and fds into.
struct LoopState {
  std::vector<std::pair<Context*, TimerEntry>> timers;
  std::vector<std::pair<Context*, FdEntry>> fds;
  std::vector<std::unique_ptr<HandlerEntry>> handlers;
  std::atomic<bool> stop{false};
};
static LoopState& loop() {
  static LoopState s;
  return s;
}

Context::Context(Bus& bus, const NodeSpec& spec, std::string instance_name,
                 std::unique_ptr<google::protobuf::Message> options,
                 std::vector<std::pair<std::string, std::string>> port_map, std::string base_dir, bool composed)
    : bus_(bus),
      spec_(spec),
      name_(std::move(instance_name)),
      options_(std::move(options)),
      port_map_(std::move(port_map)),
      base_dir_(std::move(base_dir)),
      composed_(composed) {
  if (options_) warn_yaw_units(*options_, "");
}

// A start pose's yaw (Pose2D, radians) beyond +-2 pi is almost surely degrees (`fploc node initial-pose` takes
// degrees): said once per field when the node's options are set up, for launch and replay alike.
void Context::warn_yaw_units(const google::protobuf::Message& m, const std::string& path) const {
  const auto* d = m.GetDescriptor();
  const auto* r = m.GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const auto* f = d->field(i);
    if (f->type() != google::protobuf::FieldDescriptor::TYPE_MESSAGE || f->is_repeated() || !r->HasField(m, f)) continue;
    const auto& sub = r->GetMessage(m, f);
    const std::string where = path + f->name();
    if (f->message_type()->name() == "Pose2D") {
      const auto* yf = f->message_type()->FindFieldByName("yaw");
      const double yaw = yf ? sub.GetReflection()->GetDouble(sub, yf) : 0.0;
      if (std::abs(yaw) > 2 * M_PI)
        std::cerr << "[" << name_ << "] warning: " << spec_.options_field << "." << where << ".yaw " << yaw
                  << " is outside [-2 pi, 2 pi]: yaw is in radians (" << yaw << " deg would be " << yaw * M_PI / 180
                  << ")" << std::endl;
    } else {
      warn_yaw_units(sub, where + ".");
    }
  }
}

Context::~Context() = default;

std::string Context::resolve_path(const std::string& p) const {
  if (p.empty()) return p;
  std::filesystem::path path(p);
  if (path.is_absolute() || base_dir_.empty()) return p;
  return (std::filesystem::path(base_dir_) / path).lexically_normal().string();
}

void Context::set_robot(const std::string& r) {
  // Ports mapped by the graph and ports on their default channel alike move into the robot's namespace.
  std::vector<std::pair<std::string, std::string>> m;
  for (const auto& ps : spec_.ports) {
    std::string ch = ps.default_channel;
    for (const auto& [p, c] : port_map_)
      if (p == ps.name) ch = c;
    m.emplace_back(ps.name, robot_channel(r, ch));
  }
  port_map_ = std::move(m);
  robot_ = r;
}

std::string Context::ns(const std::string& channel) const { return robot_channel(robot_, channel); }

const std::string& Context::channel(const std::string& port) const {
  for (const auto& [p, c] : port_map_)
    if (p == port) return c;
  for (const auto& ps : spec_.ports)
    if (ps.name == port) return ps.default_channel;
  throw std::runtime_error("node '" + name_ + "': no port named '" + port + "' in its spec");
}

void Context::publish_raw(const std::string& channel, const void* data, int size, PortCounters* c) {
  if (channel.empty()) return;  // output port not connected
  if (bus_.lcm().publish(channel, data, unsigned(size)) != 0) {
    if (c) ++c->dropped;
    return;
  }
  if (c) {
    ++c->messages;
    ++c->period_messages;
    c->rate.add(now_s());
  }
}

static double thread_cpu_s() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

static void deliver(HandlerEntry* h, const void* data, int size) {
  const double t0 = now_s();
  const double c0 = h->ctx->composed() ? thread_cpu_s() : 0.0;
  bool ok = false;
  try {
    ok = h->fn(data, size);
  } catch (const std::exception& e) {
    h->ctx->error(std::string("handler on ") + h->counters->channel + ": " + e.what());
    ok = true;  // decoded, but the node failed on it
  }
  h->counters->superseded = 0;  // (message types without seq: observe_seq did not reset it)
  if (!ok) {
    ++h->counters->undecodable;
    h->ctx->error("undecodable message on " + h->counters->channel + " (" + std::to_string(size) + " bytes)");
    return;
  }
  ++h->counters->messages;
  ++h->counters->period_messages;
  h->counters->rate.add(t0);
  const double dt = now_s() - t0;
  // Live nodes: per-heartbeat window (reset every second). Composed replay: every call (the breakdown
  // of `fploc replay --json`); keeping both in a live node would grow without bound.
  if (h->ctx->composed()) {
    h->ctx->stats().latency_total.add(dt * 1e3);
    h->ctx->stats().cpu_s_total += thread_cpu_s() - c0;
  } else {
    h->ctx->stats().latency.add(dt * 1e3);
    h->counters->latency.add(dt * 1e3);
  }
  h->ctx->stats().busy_s_period += dt;
}

static void raw_handler(const lcm::ReceiveBuffer* rbuf, const std::string&, HandlerEntry* h) {
  if (!h->latest) return deliver(h, rbuf->data, int(rbuf->data_size));
  // Keep-latest: the newest message waits here until run_latest(); the one it replaces is a drop.
  if (h->has_pending) {
    ++h->counters->dropped;
    ++h->counters->superseded;
  }
  const auto* p = static_cast<const uint8_t*>(rbuf->data);
  h->pending.assign(p, p + rbuf->data_size);
  h->has_pending = true;
}

void Context::subscribe_raw(const std::string& port, std::function<bool(const void*, int)> fn) {
  const std::string& ch = channel(port);
  if (ch.empty()) return;  // not connected
  auto h = std::make_unique<HandlerEntry>();
  h->ctx = this;
  h->counters = &stats_.port(port, ch, false);
  h->fn = std::move(fn);
  h->latest = !composed_ && queue(port) == Queue::kLatest;  // replay delivers every message
  auto* sub = bus_.lcm().subscribeFunction(ch, &raw_handler, h.get());
  // Composed replay drains after every event; live nodes get room for bursts.
  if (sub) sub->setQueueCapacity(composed_ ? 10000 : 100);
  loop().handlers.push_back(std::move(h));
}

Queue Context::queue(const std::string& port) const {
  for (const auto& [p, q] : queue_overrides_)
    if (p == port) return q;
  for (const auto& ps : spec_.ports)
    if (ps.name == port) return ps.queue;
  return Queue::kAll;
}

int run_latest() {
  int n = 0;
  for (auto& h : loop().handlers) {
    if (!h->has_pending) continue;
    h->has_pending = false;
    std::vector<uint8_t> msg;
    msg.swap(h->pending);  // the handler may run the loop's LCM again (not today), keep the slot free
    deliver(h.get(), msg.data(), int(msg.size()));
    ++n;
  }
  return n;
}

int dispatch_live(Bus& bus, double max_s) {
  // Everything LCM has queued first (keep-latest inputs only store theirs), so a keep-latest handler
  // sees the newest message; bounded in time so a slow keep-all node still beats and runs its timers.
  int n = 0;
  const double t_end = now_s() + max_s;
  while (bus.lcm().handleTimeout(0) > 0) {
    ++n;
    if (now_s() >= t_end) break;
  }
  return n + run_latest();
}

void Context::every(double period_s, std::function<void()> fn) {
  if (composed_) throw std::runtime_error("node '" + name_ + "': timers are not available in composed replay");
  loop().timers.push_back({this, TimerEntry{period_s, now_s() + period_s, std::move(fn)}});
}

void Context::watch_fd(int fd, std::function<void()> fn) {
  if (composed_) throw std::runtime_error("node '" + name_ + "': sockets are not available in composed replay");
  loop().fds.push_back({this, FdEntry{fd, std::move(fn)}});
}

bool Context::error(const std::string& msg) {
  ++stats_.errors;
  stats_.last_error = msg;
  if (stats_.errors <= 5 || (stats_.errors % 1000) == 0) {
    std::cerr << "[" << name_ << "] error: " << msg;
    if (stats_.errors == 5) std::cerr << " (further errors are counted in telemetry)";
    std::cerr << std::endl;
    return true;
  }
  return false;
}

void Context::set_failing(const std::string& what) {
  if (what == stats_.failing) return;
  if (what.empty()) {
    if (stats_.last_error == stats_.failing) stats_.last_error.clear();
    stats_.failing.clear();
    return;
  }
  stats_.failing = what;
  error(what);
}

bool Context::status_changed(const std::string& line, bool keep_detail, bool print) {
  stats_.detail = keep_detail ? line : std::string();
  if (!print || status_changes_ >= kStatusChangesPrinted) return false;
  ++status_changes_;
  std::cerr << "[" << name_ << "] " << line
            << (status_changes_ == kStatusChangesPrinted ? " (further changes: telemetry's detail)" : "") << std::endl;
  return true;
}

void Context::request_stop() { loop().stop = true; }

// ---- composition --------------------------------------------------------------------------------
static std::vector<std::pair<std::string, std::string>> port_map_of(const fploc::Node& n) {
  std::vector<std::pair<std::string, std::string>> m;
  for (const auto& p : n.input()) m.emplace_back(p.port(), p.channel());
  for (const auto& p : n.output()) m.emplace_back(p.port(), p.channel());
  return m;
}
static std::vector<std::pair<std::string, Queue>> queue_overrides_of(const fploc::Node& n) {
  std::vector<std::pair<std::string, Queue>> q;
  for (const auto& p : n.input())
    if (p.queue() != fploc::Port::SPEC) q.emplace_back(p.port(), p.queue() == fploc::Port::LATEST ? Queue::kLatest : Queue::kAll);
  return q;
}

Composition::Composition(const LoadedGraph& graph, Bus& bus, const std::vector<std::string>& skip) : bus_(bus) {
  for (const auto& n : graph.graph.node()) {
    if (n.disabled() || std::find(skip.begin(), skip.end(), n.name()) != skip.end()) continue;
    const auto* reg = find_registration(type_from_executable(n.executable()));
    if (!reg) continue;  // not linked into this process (e.g. drivers, dashboard)
    auto opts = node_options(n);
    ComposedNode cn;
    cn.name = n.name();
    cn.ctx = std::make_unique<Context>(bus, reg->spec, n.name(), std::move(opts), port_map_of(n), graph.dir, true);
    cn.ctx->set_robot(robot_of(&graph.graph));
    cn.node = reg->make();
    try {
      cn.node->setup(*cn.ctx);
    } catch (const std::exception& e) {
      throw std::runtime_error("node '" + n.name() + "': setup failed: " + e.what());
    }
    nodes_.push_back(std::move(cn));
  }
}

void Composition::drain() {
  while (bus_.lcm().handleTimeout(0) > 0) {
  }
}

void Composition::shutdown() {
  // In graph order, delivering what each node publishes while it shuts down (e.g. the optimizer's last
  // window) before the next node shuts down: sinks such as pose loggers belong at the end of a graph.
  drain();
  for (auto& n : nodes_) {
    n.node->shutdown();
    drain();
  }
}

std::vector<std::string> Composition::external_inputs() const {
  std::vector<std::string> produced, needed;
  for (const auto& n : nodes_)
    for (const auto& p : n.ctx->stats().ports) (p.output ? produced : needed).push_back(p.channel);
  std::vector<std::string> out;
  for (const auto& c : needed)
    if (!c.empty() && std::find(produced.begin(), produced.end(), c) == produced.end() &&
        std::find(out.begin(), out.end(), c) == out.end())
      out.push_back(c);
  return out;
}

// ---- process main -------------------------------------------------------------------------------
// A stop signal from a process other than the one that started this node (a user's `kill`, not the launcher, whose
// stops come from the parent: the launcher, or fploc-remote relaying it) -- under a launcher such a stop is a
// failure (the node exits with 128 + the signal, and the graph's restart policy applies): it exited 0 and was never
// restarted. si_pid 0: the kernel (a terminal's Ctrl-C).
static volatile sig_atomic_t g_outside_signal = 0, g_outside_pid = 0;
static void on_signal(int sig, siginfo_t* si, void*) {
  loop().stop = true;
  if (si && si->si_pid > 0 && si->si_pid != getppid()) g_outside_signal = sig, g_outside_pid = si->si_pid;
}

static fploc::node_status_t make_status(Context& ctx, const std::string& executable, const std::string& state,
                                        double cpu, double uptime, int restarts) {
  auto& st = ctx.stats();
  fploc::node_status_t s;
  s.utime = wall_utime();
  s.node = ctx.name();
  s.executable = executable;
  s.pid = getpid();
  s.state = state;
  s.reporter = "node";
  s.restarts = restarts;
  s.cpu_percent = cpu;
  s.latency_p50_ms = st.latency.percentile(0.5);
  s.latency_p99_ms = st.latency.percentile(0.99);
  s.messages_in = st.messages(false);
  s.messages_out = st.messages(true);
  s.dropped = st.dropped();
  s.undecodable = st.undecodable();
  s.last_error = st.last_error;
  if (state == "running" && !st.failing.empty()) {  // running, but not doing its job (Context::set_failing)
    s.state = "failing";
    s.last_error = st.failing;
  }
  s.detail = st.detail;
  s.uptime_s = uptime;
  const double now = now_s();
  for (auto& p : st.ports) {
    fploc::port_stats_t ps;
    ps.port = p.port;
    ps.channel = p.channel;
    ps.output = p.output;
    ps.messages = p.messages;
    ps.rate_hz = p.rate.rate_hz(now);
    ps.dropped = p.dropped;
    ps.undecodable = p.undecodable;
    ps.latency_p50_ms = p.latency.percentile(0.5);
    ps.latency_p99_ms = p.latency.percentile(0.99);
    s.ports.push_back(ps);
  }
  s.num_ports = int32_t(s.ports.size());
  s.robot = ctx.robot();
  static const std::string host = host_name();
  s.host = host;
  return s;
}

static void usage(const Registration& r) {
  std::cerr << "usage: fploc-" << r.spec.type
            << " [--graph FILE --node NAME] [--lcm-url URL] [--set field=value ...] [--describe]\n  "
            << r.spec.description << "\n";
}

int node_main(int argc, char** argv) {
  if (registry().size() != 1) {
    std::cerr << "internal error: a node executable must link exactly one node (has " << registry().size() << ")\n";
    return 2;
  }
  const Registration& reg = registry().front();
  std::string graph_path, node_name, url;
  std::vector<std::string> sets;
  bool describe = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return argv[++i];
    };
    try {
      if (a == "--graph") graph_path = next();
      else if (a == "--node") node_name = next();
      else if (a == "--lcm-url") url = next();
      else if (a == "--set") sets.push_back(next());
      else if (a == "--describe") describe = true;
      else if (a == "-h" || a == "--help") { usage(reg); return 0; }
      else { std::cerr << "fploc-" << reg.spec.type << ": unknown argument '" << a << "'\n"; usage(reg); return 2; }
    } catch (const std::exception& e) {
      std::cerr << "fploc-" << reg.spec.type << ": " << e.what() << "\n";
      return 2;
    }
  }

  if (describe) {
    std::cout << spec_json(reg.spec) << "\n";
    return 0;
  }

  // Options and ports from the graph (or defaults when run standalone).
  std::unique_ptr<google::protobuf::Message> options = default_options(reg.spec.options_field);
  std::vector<std::pair<std::string, std::string>> port_map;
  std::vector<std::pair<std::string, Queue>> queues;
  std::string base_dir = std::filesystem::current_path().string();
  std::string instance = reg.spec.type;
  std::string robot = robot_of(nullptr);
  if (!graph_path.empty()) {
    LoadedGraph g;
    std::vector<GraphError> errors;
    if (!load_graph(graph_path, g, errors)) {
      for (const auto& e : errors) std::cerr << e.str() << "\n";
      return 2;
    }
    const fploc::Node* found = nullptr;
    for (const auto& n : g.graph.node())
      if (n.name() == node_name) found = &n;
    if (!found) {
      std::cerr << graph_path << ": no node named '" << node_name << "'\n";
      return 2;
    }
    if (auto o = node_options(*found)) options = std::move(o);
    port_map = port_map_of(*found);
    queues = queue_overrides_of(*found);
    base_dir = g.dir;
    instance = node_name;
    url = graph_lcm_url(g.graph, url);
    robot = robot_of(&g.graph);
  }
  if (!sets.empty()) {
    std::string err;
    if (!options) {
      std::cerr << "fploc-" << reg.spec.type << ": --set given but this node takes no options\n";
      return 2;
    }
    if (!apply_overrides(*options, sets, err)) {
      std::cerr << "fploc-" << reg.spec.type << ": " << err << "\n";
      return 2;
    }
  }

  struct sigaction sa {};
  sa.sa_sigaction = on_signal;
  sa.sa_flags = SA_SIGINFO;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);

  const bool launched = getenv("FPLOC_RESTARTS") != nullptr;  // set by fploc launch (and fploc-remote) only
  const int restarts = launched ? atoi(getenv("FPLOC_RESTARTS")) : 0;
  std::string executable = std::string("fploc-") + reg.spec.type;
  std::replace(executable.begin(), executable.end(), '_', '-');
  try {
    Bus bus(url);
    Context ctx(bus, reg.spec, instance, std::move(options), port_map, base_dir, false);
    ctx.set_restarts(restarts);
    ctx.set_robot(robot);
    ctx.set_queue_overrides(std::move(queues));
    const std::string telemetry = ctx.ns(kTelemetryChannel);
    auto node = reg.make();
    // setup() may take long (a large plan's ANNF on a cold cache, fploc/annf/cache.h): after 2 s a
    // thread sends a "loading" heartbeat every second, so the launcher does not take a slow start for
    // a hang (killing it would also throw the half-built field away, every restart again). A quick
    // setup sends none: its first status is "running", as before.
    std::atomic<bool> setup_done{false};
    const fploc::node_status_t loading = make_status(ctx, executable, "loading", 0, 0, restarts);
    std::thread loading_beats([&] {
      for (int tick = 0; !setup_done; ++tick) {
        if (tick >= 20 && tick % 10 == 0) {
          fploc::node_status_t s = loading;
          s.utime = wall_utime();
          bus.lcm().publish(kTelemetryChannel, &s);
        }
        usleep(100000);
      }
    });
    struct JoinBeats {
      std::atomic<bool>& done;
      std::thread& t;
      ~JoinBeats() {
        done = true;
        t.join();
      }
    };
    try {
      JoinBeats join{setup_done, loading_beats};
      node->setup(ctx);
    } catch (const SetupMayPass& e) {
      std::cerr << "[" << instance << "] setup failed (may pass; restarted by the launcher's policy): " << e.what()
                << std::endl;
      auto s = make_status(ctx, executable, "dead", 0, 0, restarts);
      s.last_error = std::string("setup failed: ") + e.what();
      bus.lcm().publish(telemetry, &s);
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "[" << instance << "] setup failed: " << e.what() << std::endl;
      auto s = make_status(ctx, executable, "dead", 0, 0, restarts);
      s.last_error = std::string("setup failed: ") + e.what();
      bus.lcm().publish(telemetry, &s);
      return kSetupFailedExitCode;  // not restarted by the launcher (restart.h)
    }
    CpuMeter cpu;
    const double t_start = now_s();
    double next_beat = t_start;  // first heartbeat at once, then 1 Hz
    const int lcm_fd = bus.lcm().getFileno();
    auto beat = [&](const std::string& state) {
      auto s = make_status(ctx, executable, state, cpu.sample_percent(), now_s() - t_start, restarts);
      bus.lcm().publish(telemetry, &s);
      ctx.stats().end_period();
    };
    auto& L = loop();
    while (!L.stop) {
      double t = now_s();
      double wake = next_beat;
      for (auto& [c, te] : L.timers) wake = std::min(wake, te.next);
      std::vector<pollfd> pfds;
      pfds.push_back({lcm_fd, POLLIN, 0});
      for (auto& [c, fe] : L.fds) pfds.push_back({fe.fd, POLLIN, 0});
      // Rounded up: truncated, the last millisecond before each timer was a busy loop of poll(0) (the
      // simulator's 2 ms timer: a third of its CPU, taken from the pipeline on a loaded machine).
      const int timeout_ms = std::max(0, int(std::ceil((wake - t) * 1000.0)));
      const int r = poll(pfds.data(), pfds.size(), std::min(timeout_ms, 100));
      if (r < 0 && errno != EINTR) {
        ctx.error(std::string("poll: ") + strerror(errno));
        break;
      }
      if (r > 0) {
        if (pfds[0].revents & POLLIN) dispatch_live(bus);
        for (size_t i = 1; i < pfds.size(); ++i) {
          if (pfds[i].revents & (POLLIN | POLLERR | POLLHUP)) {
            auto& [c, fe] = L.fds[i - 1];
            const double t0 = now_s();
            try {
              fe.fn();
            } catch (const std::exception& e) {
              c->error(e.what());
            }
            c->stats().busy_s_period += now_s() - t0;
          }
        }
      }
      t = now_s();
      for (auto& [c, te] : L.timers) {
        if (t >= te.next) {
          const double t0 = now_s();
          try {
            te.fn();
          } catch (const std::exception& e) {
            c->error(e.what());
          }
          const double dt = now_s() - t0;
          c->stats().latency.add(dt * 1e3);
          c->stats().busy_s_period += dt;
          te.next = std::max(te.next + te.period, t);
        }
      }
      if (now_s() >= next_beat) {
        beat("running");
        next_beat += 1.0;
        if (next_beat < now_s()) next_beat = now_s() + 1.0;
      }
    }
    // Deliver what is queued and what is still on its way, then stop: in a graph-wide stop the producers
    // stopped just before (fploc launch stops them first) and published their last messages (a flushed
    // window, a frame in progress) a moment ago, and under CPU load LCM's receive thread may not have read
    // them from the socket yet (handleTimeout(0) sees only its queue: a pose logger lost the optimizer's
    // last poses so). Until 100 ms pass without a message, at most 1 s.
    for (const double drain_end = now_s() + 1.0; now_s() < drain_end && bus.lcm().handleTimeout(100) > 0;) {
    }
    run_latest();
    node->shutdown();
    beat("stopped");
  } catch (const std::exception& e) {
    std::cerr << "[" << instance << "] fatal: " << e.what() << std::endl;
    return 1;
  }
  if (launched && g_outside_signal) {
    std::cerr << "[" << instance << "] stopped by " << strsignal(g_outside_signal) << " from pid " << int(g_outside_pid)
              << ", not the launcher: exit code " << 128 + g_outside_signal << " (the graph's restart policy applies)"
              << std::endl;
    return 128 + g_outside_signal;
  }
  return 0;
}

}  // namespace fploc::rt
