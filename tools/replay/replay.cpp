// fploc replay --graph GRAPH --log LOG.lcm --out EST.tum [--json] [--set NODE.field=value ...]
// Runs every node of GRAPH that is linked into this process (all fploc_add_node nodes of the build) in
// one process over memq://. Events of the log are published in file order, but only on the graph's
// external inputs (channels some composed node subscribes to and none publishes); after each event the
// queue is drained completely (lock-step), so the run is deterministic and as fast as the CPU allows.
// --out sets the file of the graph's pose logger (with several: the one on FPLOC_POSE; the others write
// OUT-STEM.NODE.tum beside it). --json prints per-node timing (wall clock and the handlers' thread CPU time,
// which is what a shared machine does not distort) and the real-time factor.
// --record FILE writes what the composed nodes publish on channels matching --record-channels (an LCM
// regex; default every FPLOC_ channel but FPLOC_SEGMENTS) into an LCM log, stamped with the log time of
// the event that caused it (for `fploc map diff`, metrics on pose_t status and covariance, lcm-logplayer).
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include <fploc/frame_pose_t.hpp>
#include <fploc/pose_t.hpp>

#include "fploc/core/text_out.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"
#include "fploc/runtime/robot.h"
#include "fploc/runtime/bus.h"
#include "fploc/runtime/compose.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/log_reader.h"
#include "fploc/runtime/node.h"
#include "fploc/tools/start_pose.h"
#include "options/tools.pb.h"

using namespace fploc::rt;

namespace {
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
void usage() {
  std::cerr << "usage: fploc replay --graph GRAPH --log LOG.lcm [--out EST.tum] [--json] [--set NODE.field=value ...]\n"
               "                    [--robot R]   (the log's channels are R/...; default: the graph's robot, else $FPLOC_ROBOT)\n"
               "                    [--record OUT.lcm [--record-channels REGEX]]\n"
               "  runs the graph's nodes in one process over memq://, lock-step on the log's events\n";
}
// The shipped graph that reads a log whose channels another graph left unread ("" when none is known).
std::string graph_for_channels(const std::map<std::string, int64_t>& channels) {
  for (const auto& [c, k] : channels) {
    const std::string bare = c.substr(c.find('/') == std::string::npos ? 0 : c.rfind('/') + 1);  // robot R/...
    if (bare == "OS1_LIDAR_PACKETS" || bare == "OS1_IMU_PACKETS")
      return "The log holds Ouster packets: replay it with --graph graphs/replay-packets.pbtxt (its drivers decode them), "
             "or import the bag again with `fploc import --decode` for graphs/replay.pbtxt";
    if (bare.rfind("POINT_CLOUD", 0) == 0)
      return "The log holds point clouds (point_cloud2_t): replay it with --graph graphs/replay-clouds.pbtxt (its "
             "cloud_to_scan node makes the scans), or import the bag again with `fploc import --decode` for "
             "graphs/replay.pbtxt";
    if (bare == "LASER_SCAN")
      return "The log holds a 2D laser (laser_scan_t): replay it with --graph graphs/lidar2d.pbtxt";
  }
  return "";
}
}  // namespace

int main(int argc, char** argv) {
  std::string graph_path, log_path, out, robot, record, record_channels = "FPLOC_(?!SEGMENTS$).*";
  bool json = false, robot_given = false;
  std::vector<std::string> sets;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "fploc replay: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--graph") graph_path = next();
    else if (a == "--log") log_path = next();
    else if (a == "--out") out = next();
    else if (a == "--json") json = true;
    else if (a == "--set") sets.push_back(next());
    else if (a == "--robot") robot = next(), robot_given = true;
    else if (a == "--record") record = next();
    else if (a == "--record-channels") record_channels = next();
    else if (a == "-h" || a == "--help") { usage(); return 0; }
    else { std::cerr << "fploc replay: unexpected argument '" << a << "'\n"; usage(); return 2; }
  }
  if (graph_path.empty() || log_path.empty()) {
    usage();
    return 2;
  }
  LoadedGraph g;
  std::vector<GraphError> errors;
  if (!load_graph(graph_path, g, errors)) {
    for (const auto& e : errors) std::cerr << e.str() << "\n";
    return 1;
  }
  // --robot: the log's channels are that robot's ("R/FPLOC_SCAN", ...), whatever the graph says.
  if (robot_given) g.graph.set_robot(robot);
  // Overrides: --out for the pose logger, --set NODE.field=value for one node. With several pose loggers (a
  // graph logging several estimators), --out is the one of the pipeline's pose (FPLOC_POSE; else the first) and
  // each other one writes beside it, OUT-STEM.NODE.tum: all writing OUT overwrote each other's bytes.
  std::vector<fploc::Node*> loggers;
  for (int i = 0; i < g.graph.node_size(); ++i) {
    auto* n = g.graph.mutable_node(i);
    if (!n->disabled() && type_from_executable(n->executable()) == "pose_logger") loggers.push_back(n);
  }
  if (!out.empty() && loggers.empty()) {
    std::cerr << graph_path << ": --out given but the graph has no enabled pose logger node\n";
    return 1;
  }
  if (!out.empty()) {
    fploc::Node* main_logger = nullptr;
    for (auto* n : loggers)
      for (const auto& in : n->input())
        if (!main_logger && in.port() == "pose" && in.channel() == "FPLOC_POSE") main_logger = n;
    if (!main_logger) main_logger = loggers.front();
    const std::filesystem::path o(out);
    for (auto* n : loggers) {
      const std::string file =
          n == main_logger ? out : (o.parent_path() / (o.stem().string() + "." + n->name() + ".tum")).string();
      auto* pl = n->mutable_pose_logger();
      pl->set_file(file);
      // Its other files, when relative (graphs/ndt.pbtxt: "ndt.unc"), go beside --out's file, not into the
      // working directory: a replay writes where --out says.
      const auto beside = [&](const std::string& f) {
        return std::filesystem::path(f).is_relative() ? (std::filesystem::path(file).parent_path() / f).string() : f;
      };
      if (!pl->uncertainty_file().empty()) pl->set_uncertainty_file(beside(pl->uncertainty_file()));
      if (!pl->floor_file().empty()) pl->set_floor_file(beside(pl->floor_file()));
      if (loggers.size() > 1) std::cerr << "fploc replay: " << n->name() << " -> " << file << "\n";
    }
  }
  const LoadedGraph as_written = g;  // before --set: which start pose belongs to which plan
  std::string set_error;
  if (!apply_node_overrides(g.graph, sets, [](const fploc::Node& n) {
        const auto* reg = find_registration(type_from_executable(n.executable()));
        return reg ? reg->spec.options_field : std::string();
      }, set_error)) {
    std::cerr << "fploc replay: " << set_error << "\n";
    return 2;
  }

  // Localizing nodes left on the graph's own plan (no --set NODE.plan.file=): one line naming it, so a log is not
  // localized against the demo room's plan unawares.
  std::string own_plans;  // "matcher, optimizer -> PLAN; ...": said again after the run of a log not the simulator's
  {
    std::map<std::string, std::vector<std::string>> by_plan;  // plan file -> nodes
    for (const auto& n : g.graph.node()) {
      if (n.disabled() || !find_registration(type_from_executable(n.executable()))) continue;
      const auto opts = node_options(n);
      if (!opts) continue;
      const auto* pf = opts->GetDescriptor()->FindFieldByName("plan");
      if (!pf || pf->type() != google::protobuf::FieldDescriptor::TYPE_MESSAGE || pf->is_repeated()) continue;
      const auto& plan = opts->GetReflection()->GetMessage(*opts, pf);
      const auto* ff = plan.GetDescriptor()->FindFieldByName("file");
      if (!ff || ff->type() != google::protobuf::FieldDescriptor::TYPE_STRING) continue;
      const std::string file = plan.GetReflection()->GetString(plan, ff);
      if (file.empty()) continue;
      bool given = false;
      for (const auto& kv : sets) given |= kv.rfind(n.name() + ".plan.file=", 0) == 0;
      if (given) continue;
      const std::filesystem::path fp(file);
      by_plan[(fp.is_absolute() ? fp : (std::filesystem::path(g.dir) / fp)).lexically_normal().string()].push_back(n.name());
    }
    if (!by_plan.empty()) {
      std::cerr << "fploc replay: the graph's own plan (no --set NODE.plan.file=PLAN):";
      std::string sep = " ";
      for (const auto& [file, names] : by_plan) {
        std::string ns;
        for (const auto& x : names) ns += (ns.empty() ? "" : ", ") + x;
        std::cerr << sep << ns << " -> " << file;
        sep = "; ";
      }
      std::cerr << "\n";
      for (const auto& [file, names] : by_plan) {
        std::string ns;
        for (const auto& x : names) ns += (ns.empty() ? "" : ", ") + x;
        own_plans += (own_plans.empty() ? "" : "; ") + ns + " -> " + file;
      }
    }
  }

  // A start pose written in the graph for the graph's own plan, kept with another plan given by --set (the demo room's
  // start in the user's building: the first scans were matched there, published POOR 2.8 m off, then LOST and
  // relocalized). One warning per node, saying how to give the start or let the relocalizer search.
  {
    const auto keep = [](const fploc::Node& n) { return find_registration(type_from_executable(n.executable())) != nullptr; };
    // wait_for_initial_pose helps only where a relocalizer sends the start, to a node that has the option.
    bool relocalizer = false;
    for (const auto& n : g.graph.node()) relocalizer |= !n.disabled() && type_from_executable(n.executable()) == "relocalizer";
    auto can_wait = [&](const std::string& node) {
      for (const auto& n : g.graph.node())
        if (n.name() == node)
          if (const auto o = node_options(n); o && o->GetDescriptor()->FindFieldByName("wait_for_initial_pose")) return true;
      return false;
    };
    const auto before = fploc::tools::start_plans(as_written, keep);
    for (const auto& sp : fploc::tools::start_plans(g, keep)) {
      if (!sp.has_initial_pose || sp.ignores_initial_pose) continue;
      bool pose_given = false;
      for (const auto& kv : sets) pose_given |= kv.rfind(sp.node + ".initial_pose", 0) == 0;
      if (pose_given) continue;
      for (const auto& b : before) {
        if (b.node != sp.node || !b.has_initial_pose || b.path == sp.path) continue;
        std::string how = "give the start in it: --set " + sp.node + ".initial_pose.x=X --set " + sp.node +
                          ".initial_pose.y=Y --set " + sp.node + ".initial_pose.yaw=YAW (radians)";
        if (relocalizer && can_wait(sp.node))
          how += ", or let the relocalizer search the plan: --set " + sp.node + ".wait_for_initial_pose=true";
        char xy[96];
        std::snprintf(xy, sizeof xy, "(%.2f, %.2f)", sp.x, sp.y);
        std::cerr << "fploc replay: warning: " << sp.node << "'s initial pose " << xy << " is the graph's, written for "
                  << b.path << ", but its plan is now " << sp.path << ": " << how << "\n";
      }
    }
  }

  // A start pose outside the plan it is to be found in (a typo, the wrong plan, another frame): the run would
  // go on LOST from the first scan. One warning per node, the replay still runs (fploc/tools/start_pose.h, as
  // `fploc node initial-pose`'s check). A node that ignores its initial_pose option (wait_for_initial_pose,
  // global_localization) is not warned about it; a building is checked on the floor the node starts on (plan.floor).
  for (const auto& sp : fploc::tools::start_plans(
           g, [](const fploc::Node& n) { return find_registration(type_from_executable(n.executable())) != nullptr; })) {
    if (!sp.has_initial_pose || sp.ignores_initial_pose) continue;
    try {
      const auto c = fploc::tools::check_start_pose(sp, sp.x, sp.y);
      if (!c.text.empty()) std::cerr << "fploc replay: warning: " << sp.node << "'s initial pose " << c.text << "\n";
    } catch (const std::exception&) {
      // the node says what is wrong with its plan when it loads it
    }
  }

  try {
    Bus bus("memq://");
    std::vector<std::string> skipped;
    for (const auto& n : g.graph.node())
      if (!n.disabled() && !find_registration(type_from_executable(n.executable()))) skipped.push_back(n.name());
    Composition comp(g, bus);
    const auto external = comp.external_inputs();
    const std::set<std::string> ext(external.begin(), external.end());
    {
      std::string names, ch;
      for (auto& n : comp.nodes()) names += (names.empty() ? "" : ", ") + n.name;
      for (auto& c : external) ch += (ch.empty() ? "" : ", ") + c;
      std::cerr << "fploc replay: " << comp.nodes().size() << " nodes composed (" << names << ")";
      if (!skipped.empty()) {
        std::string s;
        for (auto& n : skipped) s += (s.empty() ? "" : ", ") + n;
        std::cerr << "; not linked into fploc-replay, left out: " << s;
      }
      std::cerr << "; fed from the log: " << (ch.empty() ? "nothing" : ch) << "\n";
    }
    if (comp.nodes().empty()) {
      std::cerr << "fploc replay: no node of " << graph_path << " is linked into fploc-replay\n";
      return 1;
    }
    fploc::rt::LogReader log(log_path);
    if (!log.good()) {
      std::cerr << "fploc replay: cannot read log '" << log_path << "'\n";
      return 1;
    }
    int64_t published = 0, t_first = -1, t_last = -1;
    std::unique_ptr<lcm::LogFile> rec;
    // What --record wrote, and every channel published during the replay (a pattern that matched none of them is
    // said at the end: it is a regular expression, and "A,B" matches no channel).
    struct Recorded {
      lcm::LogFile* file = nullptr;
      int64_t* t = nullptr;
      int64_t written = 0;
      std::map<std::string, int64_t> channels;
    } recorded;
    if (!record.empty()) {
      rec = std::make_unique<lcm::LogFile>(record, "w");
      if (!rec->good()) {
        std::cerr << "fploc replay: cannot write the record log '" << record << "'\n";
        return 1;
      }
      recorded.file = rec.get();
      recorded.t = &t_last;
      bus.lcm().subscribeFunction(record_channels, +[](const lcm::ReceiveBuffer* rb, const std::string& channel,
                                                       Recorded* ctx) {
        lcm::LogEvent ev;
        ev.eventnum = 0;
        ev.timestamp = *ctx->t;
        ev.channel = channel;
        ev.datalen = int32_t(rb->data_size);
        ev.data = rb->data;
        ctx->file->writeEvent(&ev);
        ++ctx->written;
      }, &recorded);
      bus.lcm().subscribeFunction(".*", +[](const lcm::ReceiveBuffer*, const std::string& channel, Recorded* ctx) {
        ++ctx->channels[channel];
      }, &recorded);
    }
    // The estimate's status (pose_t.status 0 OK, 1 POOR, 2 LOST) on the pose channel of the main pose logger
    // (FPLOC_POSE when there is none), for the summary line: a run that was LOST throughout said only "done".
    // The main logger as --out chooses it: the first whose pose input is FPLOC_POSE, else the first with a connected
    // pose input.
    std::string pose_channel;
    for (const auto& n : g.graph.node())
      if (!n.disabled() && type_from_executable(n.executable()) == "pose_logger")
        for (const auto& in : n.input())
          if (in.port() == "pose" && !in.channel().empty() && (pose_channel.empty() || in.channel() == "FPLOC_POSE") &&
              pose_channel != "FPLOC_POSE")
            pose_channel = in.channel();
    if (pose_channel.empty()) pose_channel = "FPLOC_POSE";
    pose_channel = fploc::rt::robot_channel(fploc::rt::robot_of(&g.graph), pose_channel);
    int64_t status_count[4] = {0, 0, 0, 0};  // OK, POOR, LOST, other
    bus.lcm().subscribeFunction(pose_channel, +[](const lcm::ReceiveBuffer* rb, const std::string&, int64_t* count) {
      fploc::pose_t p;
      if (p.decode(rb->data, 0, int(rb->data_size)) < 0) return;
      ++count[p.status >= 0 && p.status <= 2 ? p.status : 3];
    }, status_count);
    // Every channel a pose logger of the graph logs (pose_t on `pose`, frame_pose_t on `frame_pose`): its statuses
    // too (the main one above is also among them), so that a run where one estimate locked and another did not says so.
    struct Logged {
      std::string channel, logger;
      bool frame = false;
      int64_t count[4] = {0, 0, 0, 0};  // OK, POOR, LOST, 3 = no estimate yet / other
    };
    std::vector<std::unique_ptr<Logged>> logged;
    for (const auto& n : g.graph.node()) {
      if (n.disabled() || type_from_executable(n.executable()) != "pose_logger") continue;
      for (const auto& in : n.input()) {
        if (in.channel().empty() || (in.port() != "pose" && in.port() != "frame_pose")) continue;
        const std::string ch = fploc::rt::robot_channel(fploc::rt::robot_of(&g.graph), in.channel());
        bool seen = false;
        for (const auto& l : logged) seen = seen || l->channel == ch;
        if (seen) continue;
        auto l = std::make_unique<Logged>();
        l->channel = ch;
        l->logger = n.name();
        l->frame = in.port() == "frame_pose";
        if (l->frame)
          bus.lcm().subscribeFunction(ch, +[](const lcm::ReceiveBuffer* rb, const std::string&, Logged* c) {
            fploc::frame_pose_t p;
            if (p.decode(rb->data, 0, int(rb->data_size)) < 0) return;
            ++c->count[p.status >= 0 && p.status <= 2 ? p.status : 3];
          }, l.get());
        else
          bus.lcm().subscribeFunction(ch, +[](const lcm::ReceiveBuffer* rb, const std::string&, Logged* c) {
            fploc::pose_t p;
            if (p.decode(rb->data, 0, int(rb->data_size)) < 0) return;
            ++c->count[p.status >= 0 && p.status <= 2 ? p.status : 3];
          }, l.get());
        logged.push_back(std::move(l));
      }
    }
    std::map<std::string, int64_t> per_channel;
    std::map<std::string, int64_t> log_channels;  // every channel of the log (an error names them when none is fed)
    const double w0 = now_s();
    while (const lcm::LogEvent* ev = log.next()) {
      ++log_channels[ev->channel];
      if (!ext.count(ev->channel)) continue;
      if (t_first < 0) t_first = ev->timestamp;
      t_last = ev->timestamp;
      ++published;
      ++per_channel[ev->channel];
      bus.lcm().publish(ev->channel, ev->data, unsigned(ev->datalen));
      comp.drain();
    }
    comp.shutdown();
    const double wall = now_s() - w0;
    const double span = t_first >= 0 ? double(t_last - t_first) * 1e-6 : 0.0;
    double total_ms = 0, total_cpu_ms = 0;
    for (auto& n : comp.nodes()) {
      total_ms += n.ctx->stats().latency_total.sum();
      total_cpu_ms += n.ctx->stats().cpu_s_total * 1e3;
    }
    int64_t node_errors = 0;
    nlohmann::json nodes = nlohmann::json::array();
    for (auto& n : comp.nodes()) {
      auto& st = n.ctx->stats();
      const double sum = st.latency_total.sum();
      const size_t cnt = st.latency_total.size();
      node_errors += st.errors;
      nodes.push_back({{"name", n.name},
                       {"type", n.ctx->spec().type},
                       {"messages", cnt},
                       {"messages_out", st.messages(true)},
                       {"mean_ms", cnt ? sum / double(cnt) : 0.0},
                       {"p50_ms", st.latency_total.percentile(0.5)},
                       {"p99_ms", st.latency_total.percentile(0.99)},
                       {"total_ms", sum},
                       {"cpu_ms", st.cpu_s_total * 1e3},
                       {"share", total_ms > 0 ? sum / total_ms : 0.0},
                       {"errors", st.errors},
                       {"last_error", st.last_error},
                       {"detail", st.detail}});
    }
    const int64_t events = log.events();
    std::cerr << "fploc replay: " << published << " of " << events << " log events fed in " << wall << " s (log span "
              << span << " s, real-time factor " << (wall > 0 ? span / wall : 0.0) << ")"
              << (node_errors ? ", " + std::to_string(node_errors) + " node errors" : std::string()) << "\n";
    const int64_t poses = status_count[0] + status_count[1] + status_count[2] + status_count[3];
    std::cerr << "fploc replay: " << poses << " poses on " << pose_channel << ": " << status_count[0] << " OK, "
              << status_count[1] << " POOR, " << status_count[2] << " LOST"
              << (status_count[3] ? ", " + std::to_string(status_count[3]) + " other status" : std::string())
              << (poses > 0 && status_count[2] == poses ? " (every pose LOST: no estimate of the run)" : "") << "\n";
    // Some of the graph's inputs got nothing while the log holds channels the graph does not read: a point-cloud log
    // through graphs/replay.pbtxt fed its IMU and no scan, and said only "0 poses".
    if (published > 0) {
      std::string starved, unread;
      std::map<std::string, int64_t> unread_channels;
      for (const auto& c : external)
        if (!per_channel.count(c)) starved += (starved.empty() ? "" : ", ") + c;
      for (const auto& [c, k] : log_channels)
        if (!ext.count(c) && c != fploc::rt::robot_channel(fploc::rt::robot_of(&g.graph), "FPLOC_GROUND_TRUTH")) {
          unread += (unread.empty() ? "" : ", ") + fploc::printable(c) + " (" + std::to_string(k) + ")";
          unread_channels[c] = k;
        }
      if (!starved.empty() && !unread.empty()) {
        std::cerr << "fploc replay: warning: " << log_path << " has no event on " << starved << ", which " << graph_path
                  << " reads; the log's channels it does not read: " << unread;
        if (const std::string hint = graph_for_channels(unread_channels); !hint.empty()) std::cerr << ". " << hint;
        std::cerr << "\n";
      }
    }
    nlohmann::json logged_json = nlohmann::json::array();
    for (const auto& l : logged) {
      const int64_t n = l->count[0] + l->count[1] + l->count[2] + l->count[3];
      logged_json.push_back({{"channel", l->channel}, {"logger", l->logger}, {"poses", n}, {"ok", l->count[0]},
                             {"poor", l->count[1]}, {"lost", l->count[2]}, {"no_estimate", l->count[3]}});
      if (l->channel == pose_channel) continue;  // said above
      std::cerr << "fploc replay: " << n << " poses on " << l->channel << " (" << l->logger << "): " << l->count[0] << " OK, "
                << l->count[1] << " POOR, " << l->count[2] << " LOST"
                << (l->count[3] ? ", " + std::to_string(l->count[3]) + " no estimate yet (not logged)" : std::string())
                << (n > 0 && l->count[2] + l->count[3] == n ? " (no estimate of the run)" : "") << "\n";
    }
    // A log that is not the simulator's (no ground truth in it: a real recording, an import) localized against the
    // graph's own plan, which for the shipped graphs is a demo plan (data/plans/): its poses are no estimate of where
    // that robot was. Said last, where the summary is read (the start's "own plan" line scrolls away).
    const std::string truth = fploc::rt::robot_channel(fploc::rt::robot_of(&g.graph), "FPLOC_GROUND_TRUTH");
    if (!own_plans.empty() && published > 0 && !log_channels.count(truth)) {
      std::cerr << "fploc replay: WARNING: " << log_path << " has no " << truth << " (not a simulator log: a recording "
                << "or an import), yet it was localized against the graph's own plan (" << own_plans << "), a demo plan "
                << "unless this log was made there. Its poses are then no estimate: pass the log's map or plan to each "
                << "node, --set NODE.plan.file=PLAN (and NODE.initial_pose.x/y/yaw; fploc occupancy MAP --png OUT --pose "
                << "X,Y,YAW --scan LOG draws a scan at a guess).\n";
    }
    if (rec && recorded.written == 0) {
      std::string seen;
      for (const auto& [c, k] : recorded.channels) seen += (seen.empty() ? "" : ", ") + fploc::printable(c);
      std::cerr << "fploc replay: warning: --record " << record << " is empty: --record-channels '"
                << fploc::printable(record_channels) << "' matched none of the channels of the run ("
                << (seen.empty() ? "none" : seen) << "); it is a regular expression (LCM's), so join names with '|', "
                << "e.g. 'FPLOC_POSE|FPLOC_FEATURES'\n";
    }
    if (json) {
      nlohmann::json j{{"log_events", events},
                       {"events_fed", published},
                       {"channels_fed", per_channel},
                       {"log_duration_s", span},
                       {"wall_s", wall},
                       {"real_time_factor", wall > 0 ? span / wall : 0.0},
                       {"handler_ms", total_ms},
                       {"handler_cpu_ms", total_cpu_ms},
                       {"nodes", nodes},
                       {"poses", {{"channel", pose_channel}, {"ok", status_count[0]}, {"poor", status_count[1]},
                                  {"lost", status_count[2]}}},
                       {"pose_channels", logged_json},
                       {"own_plan_without_truth", !own_plans.empty() && published > 0 && !log_channels.count(
                           fploc::rt::robot_channel(fploc::rt::robot_of(&g.graph), "FPLOC_GROUND_TRUTH"))}};
      if (!out.empty()) j["out"] = out;
      std::cout << fploc::json_text(j) << std::endl;
    }
    if (published == 0 && events > 0) {
      // Nothing of the log reached the graph: its nodes ran on nothing (poses, if any, are no estimate of it).
      std::string have, want;
      for (const auto& [c, k] : log_channels) have += (have.empty() ? "" : ", ") + fploc::printable(c) + " (" + std::to_string(k) + ")";
      for (const auto& c : external) want += (want.empty() ? "" : ", ") + c;
      std::cerr << "fploc replay: no event of " << log_path << " is on an input channel of " << graph_path
                << ": the log holds " << have << "; the graph reads " << (want.empty() ? "nothing from outside" : want);
      if (const std::string hint = graph_for_channels(log_channels); !hint.empty()) std::cerr << ". " << hint;
      std::cerr << "\n";
      return 1;
    }
    if (const std::string problem = log.problem(); !problem.empty()) {
      std::cerr << "fploc replay: " << problem << (events > 0 ? "; the events read were replayed" : "") << "\n";
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fploc replay: " << e.what() << "\n";
    return 1;
  }
}
