// fploc map diff --graph G --log LOG.lcm --out diff.json|diff.dxf [--out ...] [--json]
// Offline plan-change detection over a recorded run: the LOG holds the wall features (features_t) and the
// localizer's estimate of each scan (pose_t with the same utime) on the channels the graph's plan_diff node
// reads (default FPLOC_FEATURES and FPLOC_POSE_LATEST) — a live run recorded with lcm-logger, or
// `fploc replay --graph G --log SIM.lcm --record LOG.lcm`. The plan and the detector's options come from
// the graph's plan_diff node (or, without one, the plan of its matcher); --plan FILE [--floor NAME] names the plan
// instead. The first line on stderr says which plan and where it came from; a matcher / optimizer of the graph with
// another plan, and a run in which no plan element was seen, are warned about (the wrong plan, most likely).
// Writes JSON and/or DXF (layers FPLOC-MISSING, FPLOC-MOVED, FPLOC-NEW, FPLOC-LOW, FPLOC-PLAN) by the --out extension; --json
// prints the JSON diff on stdout; --all lists every element (also those seen where expected); --set
// NODE.field=value as for fploc replay (the plan_diff node's options: plan_diff.plan.file=PLAN, ...). The summary
// on stderr: counts (with missing parts), the drawing scale, then one line per missing / moved element, missing
// part and new run (plandiff::write_text).
// --poses FILE.tum (diagnostic): each scan placed with the pose of FILE nearest its time (within 5 ms; e.g. the
// simulator's ground truth) instead of the localizer's, no covariance: what the detector finds with good poses.
#include <fploc/features_t.hpp>
#include <fploc/segments_t.hpp>
#include "fploc/adapters/plan_diff_t.h"
#include <fploc/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fploc/config/plandiff.h"
#include "fploc/core/pose.h"
#include "fploc/floorplan/io.h"
#include "fploc/plandiff/plan_diff.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/log_reader.h"

namespace {

void usage() {
  std::cerr << "usage: fploc map diff --graph GRAPH --log LOG.lcm --out DIFF.json|DIFF.dxf [--out ...] [--json]\n"
               "       [--features-channel C] [--pose-channel C] [--all (every element in the JSON, also those seen)]\n"
               "       [--plan PLAN [--floor NAME]] (the plan to diff against, read as it is: every layer, the file's own\n"
               "       units; default: the graph's plan_diff node's plan with its layers and units)\n"
               "       [--set NODE.field=value ...] (the graph's node options, as for fploc replay: e.g.\n"
               "        plan_diff.plan.file=PLAN; a matcher's plan is not the diff's plan)\n"
               "       [--poses FILE.tum] (place each scan with these poses, e.g. the ground truth, not the localizer's)\n";
}

std::string lower_ext(const std::string& p) {
  std::string e = std::filesystem::path(p).extension().string();
  for (auto& c : e) c = char(std::tolower((unsigned char)c));
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  std::string graph_path, log_path, feat_ch, pose_ch, poses_path, plan_arg, floor_arg;
  std::vector<std::string> outs, sets;
  bool json = false, all = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "fploc map diff: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--graph") graph_path = next();
    else if (a == "--log") log_path = next();
    else if (a == "--out") outs.push_back(next());
    else if (a == "--features-channel") feat_ch = next();
    else if (a == "--pose-channel") pose_ch = next();
    else if (a == "--set") sets.push_back(next());
    else if (a == "--poses") poses_path = next();
    else if (a == "--plan") plan_arg = next();
    else if (a == "--floor") floor_arg = next();
    else if (a == "--json") json = true;
    else if (a == "--all") all = true;
    else if (a == "-h" || a == "--help") { usage(); return 0; }
    else { std::cerr << "fploc map diff: unexpected argument '" << a << "'\n"; usage(); return 2; }
  }
  if (graph_path.empty() || log_path.empty() || (outs.empty() && !json)) {
    usage();
    return 2;
  }
  if (!floor_arg.empty() && plan_arg.empty()) {
    std::cerr << "fploc map diff: --floor needs --plan (the graph's plan.floor: --set plan_diff.plan.floor=NAME)\n";
    return 2;
  }
  for (const auto& o : outs)
    if (lower_ext(o) != ".json" && lower_ext(o) != ".dxf") {
      std::cerr << "fploc map diff: --out " << o << ": expected a .json or .dxf file\n";
      return 2;
    }
  try {
    fploc::rt::LoadedGraph g;
    std::vector<fploc::rt::GraphError> errors;
    if (!fploc::rt::load_graph(graph_path, g, errors)) {
      for (const auto& e : errors) std::cerr << e.str() << "\n";
      return 1;
    }
    // The run's --set (its plan above all: without it the diff was against the graph file's plan, not the run's).
    std::string set_error;
    if (!fploc::rt::apply_node_overrides(g.graph, sets, {}, set_error)) {
      std::cerr << "fploc map diff: " << set_error << "\n";
      return 2;
    }
    const fploc::Node* node = nullptr;
    const fploc::PlanSource* src = nullptr;
    std::string src_what;  // where the plan comes from, said on the first line
    fploc::plandiff::Options po;
    std::string seg_ch = "FPLOC_SEGMENTS";  // the 3D wall points: how tall new structure is (when the log has them)
    for (const auto& n : g.graph.node()) {
      if (n.has_plan_diff() && !node) {
        node = &n;
        src = &n.plan_diff().plan();
        src_what = "the graph's plan_diff node '" + n.name() + "' (plan.file)";
        po = fploc::config::config_of(n.plan_diff()).diff;  // as the node maps them (a negative one: an error)
        for (const auto& in : n.input()) {
          if (in.port() == "features" && feat_ch.empty()) feat_ch = in.channel();
          if (in.port() == "pose" && pose_ch.empty()) pose_ch = in.channel();
          if (in.port() == "segments" && !in.channel().empty()) seg_ch = in.channel();
        }
      }
    }
    if (!src)
      for (const auto& n : g.graph.node())
        if (n.has_matcher() && !n.disabled() && !src) {
          src = &n.matcher().plan();
          src_what = "the graph's matcher '" + n.name() + "' (no plan_diff node)";
        }
    if (plan_arg.empty() && (!src || src->file().empty()))
      throw std::runtime_error(graph_path + ": no plan_diff node (and no matcher) names a plan; name one with --plan");
    if (feat_ch.empty()) feat_ch = "FPLOC_FEATURES";
    if (pose_ch.empty()) pose_ch = "FPLOC_POSE_LATEST";
    auto graph_relative = [&](std::string f) {
      if (!f.empty() && f[0] != '/')
        f = (std::filesystem::path(graph_path).parent_path() / f).lexically_normal().string();
      return f;
    };
    std::string plan_file;
    fploc::FloorPlan plan;
    if (!plan_arg.empty()) {
      plan_file = std::filesystem::path(plan_arg).lexically_normal().string();
      src_what = "--plan";
      plan = fploc::load_floor_plan(plan_file, {}, "", floor_arg);
      if (!floor_arg.empty()) plan_file += " (floor " + floor_arg + ")";
    } else {
      plan_file = graph_relative(src->file());
      std::vector<std::string> layers(src->layers().begin(), src->layers().end());
      // The floor the graph names (plan.floor; a building or IFC model's first / lowest by default), as the node loads it.
      plan = fploc::load_floor_plan(plan_file, layers, src->units(), src->floor());
      if (!src->floor().empty()) plan_file += " (floor " + src->floor() + ")";
    }
    // Said first once the log has been read (an error reading it stays one line).
    std::ostringstream preface;
    preface << "fploc map diff: the plan: " << plan_file << ", from " << src_what << "\n";
    // The poses were estimated against the matcher's / optimizer's plan: another plan there is most likely a run
    // replayed with --set matcher.plan.file=X, whose diff must name X too.
    // (Not when the diff's plan was named explicitly: --plan, or --set NODE.plan.file for the plan_diff node.)
    bool plan_set = false;
    for (const auto& st : sets)
      if (node && st.rfind(node->name() + ".plan.file=", 0) == 0) plan_set = true;
    if (plan_arg.empty() && !plan_set)
      for (const auto& n : g.graph.node()) {
        if (n.disabled() || (!n.has_matcher() && !n.has_optimizer())) continue;
        const auto& ps = n.has_matcher() ? n.matcher().plan() : n.optimizer().plan();
        if (ps.file().empty() || (graph_relative(ps.file()) == graph_relative(src->file()) && ps.floor() == src->floor()))
          continue;
        preface << "fploc map diff: warning: the graph's " << (n.has_matcher() ? "matcher" : "optimizer") << " '"
                  << n.name() << "' localizes against " << graph_relative(ps.file())
                  << (ps.floor().empty() ? "" : " (floor " + ps.floor() + ")") << ", not the plan diffed against; if that is the run's plan: --plan "
                  << graph_relative(ps.file()) << "\n";
      }
    fploc::plandiff::PlanDiff diff(plan, po);

    // --poses: the scans placed with a given trajectory (sorted by time), looked up at each scan's time.
    fploc::Trajectory given;
    if (!poses_path.empty()) {
      given = fploc::read_tum(poses_path);
      if (given.empty()) throw std::runtime_error(poses_path + ": no poses");
      std::stable_sort(given.begin(), given.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
    }
    int64_t unmatched = 0;
    auto given_at = [&](double t) -> const fploc::StampedPose* {
      auto it = std::lower_bound(given.begin(), given.end(), t, [](const auto& p, double v) { return p.t < v; });
      const fploc::StampedPose* best = nullptr;
      if (it != given.end()) best = &*it;
      if (it != given.begin() && (!best || std::abs(std::prev(it)->t - t) < std::abs(best->t - t))) best = &*std::prev(it);
      return best && std::abs(best->t - t) <= 0.005 ? best : nullptr;
    };
    fploc::rt::LogReader log(log_path);
    if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");
    std::map<int64_t, fploc::features_t> feats;
    std::map<int64_t, fploc::plandiff::PlanDiff::Heights> heights;  // by utime, as the features
    auto heights_at = [&](int64_t utime) -> const fploc::plandiff::PlanDiff::Heights* {
      const auto it = heights.find(utime);
      return it == heights.end() ? nullptr : &it->second;
    };
    int64_t events = 0, n_feat = 0, n_pose = 0, n_seg = 0, used = 0, bad = 0;
    while (const lcm::LogEvent* ev = log.next()) {
      ++events;
      if (ev->channel == seg_ch && po.new_min_height_m > 0) {
        fploc::segments_t sg;
        if (sg.decode(ev->data, 0, ev->datalen) < 0) {
          if (bad++ == 0) std::cerr << "fploc map diff: " << log_path << ": event " << events << " on " << seg_ch << " does not decode as segments_t (skipped)\n";
          continue;
        }
        ++n_seg;
        heights[sg.utime] = fploc::adapters::heights_of(sg);
        while (heights.size() > 50) heights.erase(heights.begin());
      } else if (ev->channel == feat_ch) {
        fploc::features_t f;
        if (f.decode(ev->data, 0, ev->datalen) < 0) {
          if (bad++ == 0) std::cerr << "fploc map diff: " << log_path << ": event " << events << " on " << feat_ch << " does not decode as features_t (skipped)\n";
          continue;
        }
        ++n_feat;
        if (!given.empty()) {
          // The given trajectory places the scan (no localizer, no covariance).
          if (f.status != 0) continue;
          const fploc::StampedPose* g = given_at(double(f.utime) * 1e-6);
          if (!g) {
            ++unmatched;
            continue;
          }
          std::vector<Eigen::Vector2f> pts;
          for (int i = 0; i < f.num_points; ++i) pts.emplace_back(f.x[size_t(i)], f.y[size_t(i)]);
          diff.add_frame(g->p.x(), g->p.y(), g->rpy().z(), pts, nullptr, true, heights_at(f.utime));
          ++used;
          continue;
        }
        feats[f.utime] = std::move(f);
        while (feats.size() > 50) feats.erase(feats.begin());
      } else if (ev->channel == pose_ch && given.empty()) {
        fploc::pose_t p;
        if (p.decode(ev->data, 0, ev->datalen) < 0) {
          if (bad++ == 0) std::cerr << "fploc map diff: " << log_path << ": event " << events << " on " << pose_ch << " does not decode as pose_t (skipped)\n";
          continue;
        }
        ++n_pose;
        const auto it = feats.find(p.utime);
        if (it == feats.end() || p.status == 2 || it->second.status != 0) continue;
        const double* q = p.orientation;
        const double yaw = std::atan2(2 * (q[3] * q[2] + q[0] * q[1]), 1 - 2 * (q[1] * q[1] + q[2] * q[2]));
        std::vector<Eigen::Vector2f> pts;
        for (int i = 0; i < it->second.num_points; ++i) pts.emplace_back(it->second.x[size_t(i)], it->second.y[size_t(i)]);
        Eigen::Matrix3d cov;  // pose_t's covariance is x y z roll pitch yaw: (x, y, yaw) = indices 0, 1, 5
        const int ix[3] = {0, 1, 5};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) cov(r, c) = p.covariance[ix[r] * 6 + ix[c]];
        diff.add_frame(p.position[0], p.position[1], yaw, pts, &cov, p.status == 0, heights_at(p.utime));  // POOR: no change evidence
        ++used;
      }
    }
    // Not an LCM log at all (a world file, a ROS bag): the reader's own words, not "no features".
    if (events == 0 && !log.problem().empty()) throw std::runtime_error(log.problem());
    if (n_feat == 0)
      throw std::runtime_error(log_path + ": no " + feat_ch + " (features_t) events in " + std::to_string(events) +
                               " log events; record a run with them (lcm-logger during `fploc launch`, or `fploc replay --graph " +
                               graph_path + " --log SIM.lcm --record LOG.lcm --record-channels 'FPLOC_.*'`: --record's default leaves "
                               "FPLOC_SEGMENTS out, and without it the heights of new structure are not checked)");
    if (!given.empty() && used == 0)
      throw std::runtime_error(poses_path + ": no pose within 5 ms of any of the " + std::to_string(n_feat) + " " +
                               feat_ch + " scans");
    if (given.empty() && n_pose == 0)
      throw std::runtime_error(log_path + ": no " + pose_ch + " (pose_t) events in " + std::to_string(events) + " log events");
    if (used == 0)
      throw std::runtime_error(log_path + ": no " + pose_ch + " pose has the utime of a " + feat_ch + " scan (" +
                               std::to_string(n_feat) + " scans, " + std::to_string(n_pose) + " poses)");
    if (po.new_min_height_m > 0 && n_seg == 0)
      preface << "fploc map diff: " << log_path << " has no " << seg_ch << " (segments_t): the heights of new structure "
              << "were not checked (a new run may be furniture); record them too (`fploc replay ... --record LOG.lcm "
              << "--record-channels 'FPLOC_.*'`: the default leaves FPLOC_SEGMENTS out)\n";
    std::cerr << preface.str();
    const auto r = diff.result();
    for (const auto& o : outs) {
      std::ofstream f(o);
      if (!f) throw std::runtime_error(o + ": cannot write");
      if (lower_ext(o) == ".json") fploc::plandiff::write_json(r, plan, f, all);
      else fploc::plandiff::write_dxf(r, plan, f);
      if (!f) throw std::runtime_error(o + ": write failed");
    }
    if (!given.empty())
      std::cerr << "fploc map diff: scans placed with the poses of " << poses_path << " (" << unmatched
                << " scans without one within 5 ms, left out)\n";
    std::cerr << "fploc map diff: " << used << " scans of " << log_path << " against " << plan_file << ": ";
    fploc::plandiff::write_text(r, plan, std::cerr);
    // Nothing of the plan where the scans were placed: most likely another building's plan (or poses in another
    // frame), not a building torn down.
    if (used >= 20 && r.count(fploc::plandiff::Status::kSeen) == 0 && r.count(fploc::plandiff::Status::kMoved) == 0)
      std::cerr << "fploc map diff: warning: no plan element was seen in " << used << " scans: is " << plan_file
                << " the plan of this log? (--plan PLAN names the run's plan)\n";
    if (json) fploc::plandiff::write_json(r, plan, std::cout, all);
    // A log cut short (or damaged part way): the diff above is of the events before it; said, exit 1, as fploc
    // replay does.
    if (const std::string problem = log.problem(); !problem.empty()) {
      std::cerr << "fploc map diff: " << problem << "; the diff is of the events read\n";
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "fploc map diff: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
