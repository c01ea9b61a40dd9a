// fploc node restart NAME [--exe EXE] [--set field=value ...] [--graph G | --lcm-url URL] [--token T]
//                                                             [--timeout S] [--no-wait]
// fploc node stop NAME / fploc node start NAME
// fploc node initial-pose X Y YAW_DEG [--graph G | --lcm-url URL] [--channel C] [--force] [--no-wait]
//   (re-)initialises the matcher: a pose_t on FPLOC_INITIAL_POSE (an operator's "2D pose estimate"), checked
//   against the graph's plans first, then says whether any node of the graph was heard (see initial_pose()).
// Publishes a node_command_t on the launcher's control channel and waits until the node reports back
// from its new process (or the launcher rejects the request, naming why).
#include <fploc/node_command_t.hpp>
#include <fploc/node_status_t.hpp>
#include <fploc/pose_t.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "fploc/runtime/bus.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/robot.h"
#include "fploc/tools/start_pose.h"

using namespace fploc::rt;

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
void usage() {
  std::cerr << "usage: fploc node restart|stop|start NAME [--exe EXECUTABLE] [--set field=value ...]\n"
               "                  [--graph GRAPH | --lcm-url URL] [--robot R] [--token T] [--timeout S] [--no-wait]\n"
               "       fploc node initial-pose X Y YAW_DEG [--graph GRAPH | --lcm-url URL] [--robot R] [--channel C]\n"
               "                  [--force] [--no-wait]\n"
               "  initial-pose: with --graph, a pose more than 2 m outside the plan of every localizing node of the\n"
               "    graph (a `plan` and an `initial_pose` option) is refused (exit 2; --force sends it), one just outside\n"
               "    or not between the drawn walls is sent with a warning. After sending, listens 1.5 s for the nodes'\n"
               "    heartbeats: exit 0 when a node (of the graph) was heard, 1 when nothing listens (--no-wait: 0 at once),\n"
               "    2 for bad arguments or a refused pose\n"
               "  --robot R: the robot's channels (R/FPLOC_CONTROL, ...); default: the graph's robot, else $FPLOC_ROBOT\n";
}

LoadedGraph load_or_exit(const std::string& path) {
  LoadedGraph g;
  std::vector<GraphError> errors;
  if (!load_graph(path, g, errors)) {
    for (const auto& e : errors) std::cerr << e.str() << "\n";
    std::exit(2);
  }
  return g;
}

// fploc node initial-pose X Y YAW_DEG: one pose_t (z, roll, pitch 0; the segmenter supplies them).
// With --graph the pose is first checked against the plans of the graph's localizing nodes (those with a `plan`
// and an `initial_pose` option: fploc/tools/start_pose.h, as `fploc replay`'s warning): more than kFarOutsideM
// outside every one of them it is refused (exit 2; --force sends it anyway), nearer or within the extent but not
// between the drawn walls it is sent with a warning. Then the tool listens on the telemetry channel for
// kListenS: when no node of the graph (without --graph: no node at all) is heard, nothing received the pose
// (exit 1; --no-wait: exit 0 after sending, nothing heard).
constexpr double kListenS = 1.5;  // heartbeats are 1 Hz

struct Heard {
  std::vector<std::string> graph_nodes;  // empty: any node counts
  std::vector<std::string> heard;
  void on(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) {
    if (m->reporter != "node" || m->state == "stopped" || m->state == "dead") return;
    if (!graph_nodes.empty() && std::find(graph_nodes.begin(), graph_nodes.end(), m->node) == graph_nodes.end()) return;
    if (std::find(heard.begin(), heard.end(), m->node) == heard.end()) heard.push_back(m->node);
  }
};

int initial_pose(int argc, char** argv) {
  if (argc < 5) {
    usage();
    return 2;
  }
  double v[3];
  for (int k = 0; k < 3; ++k) {
    char* end = nullptr;
    v[k] = std::strtod(argv[2 + k], &end);
    if (end == argv[2 + k] || *end != '\0' || !std::isfinite(v[k])) {
      std::cerr << "fploc node initial-pose: '" << argv[2 + k] << "' is not a number (X Y YAW_DEG)\n";
      return 2;
    }
  }
  std::string url = getenv("FPLOC_LCM_URL") ? getenv("FPLOC_LCM_URL") : "";
  std::string channel = kInitialPoseChannel;
  std::string robot = robot_of(nullptr);
  std::string graph_path;
  bool force = false, wait = true;
  Heard heard;
  std::vector<fploc::tools::StartPlan> plans;
  for (int i = 5; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--force") {
      force = true;
      continue;
    }
    if (a == "--no-wait") {
      wait = false;
      continue;
    }
    if (i + 1 >= argc) {
      std::cerr << "fploc node initial-pose: " << a << " needs a value\n";
      return 2;
    }
    if (a == "--lcm-url") url = argv[++i];
    else if (a == "--graph") {
      graph_path = argv[++i];
      const LoadedGraph g = load_or_exit(graph_path);
      url = graph_lcm_url(g.graph, url);
      robot = robot_of(&g.graph);
      plans = fploc::tools::start_plans(g);
      heard.graph_nodes.clear();
      for (const auto& n : g.graph.node())
        if (!n.disabled()) heard.graph_nodes.push_back(n.name());
    } else if (a == "--robot") robot = argv[++i];
    else if (a == "--channel") channel = argv[++i];
    else {
      std::cerr << "fploc node initial-pose: unexpected argument '" << a << "'\n";
      return 2;
    }
  }
  // The pose against the plans of the graph's localizing nodes.
  int far = 0, checked = 0;
  std::vector<std::pair<bool, std::string>> said;  // (far outside, what)
  for (const auto& sp : plans) {
    fploc::tools::StartPoseCheck c;
    try {
      c = fploc::tools::check_start_pose(sp, v[0], v[1]);
    } catch (const std::exception& e) {
      said.emplace_back(false, "cannot check the pose against " + sp.node + "'s plan: " + e.what());
      continue;
    }
    ++checked;
    if (c.kind == fploc::tools::StartPoseKind::kInside) continue;
    const bool is_far = c.kind == fploc::tools::StartPoseKind::kFarOutside;
    far += is_far;
    std::ostringstream o;
    o << "for " << sp.node << " the pose " << c.text;
    if (!c.where.inside_extent()) o << ", " << c.where.outside_m << " m beyond it";
    said.emplace_back(is_far, o.str());
  }
  const bool refuse = checked > 0 && far == checked && !force;
  for (const auto& [is_far, w] : said)
    std::cerr << "fploc node initial-pose: " << (is_far && refuse ? "error" : "warning") << ": " << w << "\n";
  if (refuse) {
    std::cerr << "fploc node initial-pose: not sent: more than " << fploc::tools::kFarOutsideM
              << " m outside the plan of every localizing node of " << graph_path << " (--force sends it anyway)\n";
    return 2;
  }
  if (!graph_path.empty() && plans.empty())
    std::cerr << "fploc node initial-pose: note: no node of " << graph_path
              << " has a plan and an initial_pose option: the pose is not checked\n";

  fploc::pose_t p{};
  p.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                std::chrono::system_clock::now().time_since_epoch()).count();
  p.final_estimate = true;
  p.floor_index = -1;  // unknown: the matcher stays on its floor
  p.position[0] = v[0];
  p.position[1] = v[1];
  const double half = 0.5 * v[2] * M_PI / 180.0;
  p.orientation[2] = std::sin(half);
  p.orientation[3] = std::cos(half);
  try {
    channel = robot_channel(robot, channel);
    Bus bus(url);
    bus.lcm().subscribe(robot_channel(robot, kTelemetryChannel), &Heard::on, &heard);
    bus.lcm().publish(channel, &p);
    std::cerr << "fploc node: initial pose x " << v[0] << " y " << v[1] << " yaw " << v[2] << " deg sent on "
              << channel << " (" << bus.url() << ")\n";
    if (!wait) return 0;
    const double t0 = now_s();
    while (now_s() - t0 < kListenS && heard.heard.empty()) bus.lcm().handleTimeout(100);
    if (heard.heard.empty()) {
      std::cerr << "fploc node: nothing listening: no node " << (graph_path.empty() ? "" : "of " + graph_path + " ")
                << "heard on " << robot_channel(robot, kTelemetryChannel) << " within " << kListenS
                << " s: is the graph running? (fploc launch " << (graph_path.empty() ? "GRAPH" : graph_path) << ")\n";
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fploc node: " << e.what() << "\n";
    return 1;
  }
}
struct Watch {
  std::string node;
  bool learning = true;
  int old_pid = -1;
  int new_pid = -1;
  std::string rejected, state;
  void on(const lcm::ReceiveBuffer*, const std::string&, const fploc::node_status_t* m) {
    if (m->node != node) return;
    if (m->reporter == "launcher") {
      if (m->state == "rejected") rejected = m->last_error;
      state = m->state;
      return;
    }
    if (learning) {
      if (m->state == "running" || m->state == "failing") old_pid = m->pid;
      return;
    }
    if (m->pid != old_pid && (m->state == "running" || m->state == "failing")) new_pid = m->pid;
    if (m->state == "stopped") state = "stopped";
  }
};
}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "initial-pose") return initial_pose(argc, argv);
  if (argc < 3) {
    usage();
    return 2;
  }
  fploc::node_command_t cmd{};
  cmd.action = argv[1];
  cmd.node = argv[2];
  std::string url = getenv("FPLOC_LCM_URL") ? getenv("FPLOC_LCM_URL") : "";
  std::string channel = kControlChannel;
  std::string robot = robot_of(nullptr);
  double timeout = 10;
  bool wait = true;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "fploc node: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--exe") cmd.executable = next();
    else if (a == "--set") cmd.set.push_back(next());
    else if (a == "--lcm-url") url = next();
    else if (a == "--token") cmd.token = next();
    else if (a == "--timeout") timeout = std::atof(next().c_str());
    else if (a == "--no-wait") wait = false;
    else if (a == "--robot") robot = next();
    else if (a == "--graph") {
      const LoadedGraph g = load_or_exit(next());
      url = graph_lcm_url(g.graph, url);
      robot = robot_of(&g.graph);
      if (!g.graph.control_channel().empty()) channel = g.graph.control_channel();
      if (cmd.token.empty()) cmd.token = g.graph.control_token();
    } else {
      std::cerr << "fploc node: unexpected argument '" << a << "'\n";
      usage();
      return 2;
    }
  }
  if (cmd.action != "restart" && cmd.action != "stop" && cmd.action != "start") {
    usage();
    return 2;
  }
  cmd.num_set = int32_t(cmd.set.size());
  channel = robot_channel(robot, channel);
  try {
    Bus bus(url);
    Watch w;
    w.node = cmd.node;
    bus.lcm().subscribe(robot_channel(robot, kTelemetryChannel), &Watch::on, &w);
    // Learn the current process from its heartbeat (1 Hz) so that its successor can be recognised.
    const double t_learn = now_s();
    while (wait && w.old_pid < 0 && now_s() - t_learn < 1.5) bus.lcm().handleTimeout(100);
    w.learning = false;
    const auto sent = std::chrono::system_clock::now();
    cmd.utime = std::chrono::duration_cast<std::chrono::microseconds>(sent.time_since_epoch()).count();
    bus.lcm().publish(channel, &cmd);
    std::cerr << "fploc node: " << cmd.action << " '" << cmd.node << "' sent on " << channel << "\n";
    if (!wait) return 0;
    const double t0 = now_s();
    while (now_s() - t0 < timeout) {
      bus.lcm().handleTimeout(50);
      if (!w.rejected.empty()) {
        std::cerr << "fploc node: rejected by the launcher: " << w.rejected << "\n";
        return 1;
      }
      if (cmd.action == "stop" && w.state == "stopped") {
        std::cerr << "fploc node: '" << cmd.node << "' stopped\n";
        return 0;
      }
      if (cmd.action != "stop" && w.new_pid > 0) {
        std::cerr << "fploc node: '" << cmd.node << "' running again as pid " << w.new_pid
                  << (w.old_pid > 0 ? " (was " + std::to_string(w.old_pid) + ")" : std::string()) << " after "
                  << int((now_s() - t0) * 1000) << " ms\n";
        return 0;
      }
    }
    std::cerr << "fploc node: no answer within " << timeout << " s (is `fploc launch` running on " << bus.url()
              << "?)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "fploc node: " << e.what() << "\n";
    return 1;
  }
}
