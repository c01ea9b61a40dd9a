#include "check_files.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/reflection.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>

#include "fploc/config/check.h"
#include "fploc/floorplan/io.h"
#include "fploc/os1/metadata.h"

namespace fploc::launch {
namespace fs = std::filesystem;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

namespace {

struct Ctx {
  const fploc::rt::LoadedGraph& g;
  std::vector<fploc::rt::GraphError>& errors;
  std::set<std::string> written;  // files some node writes at run time (metadata_out)
  int node = 0;
  std::string field;              // top-level options field name (for the line)
  bool remote = false;            // the node runs on another host: the folders it writes to are that host's
};

std::string resolve(const fploc::rt::LoadedGraph& g, const std::string& p) {
  if (p.empty() || fs::path(p).is_absolute() || g.dir.empty()) return p;
  return (fs::path(g.dir) / p).lexically_normal().string();
}

void add(Ctx& c, const std::string& what, const std::string& path, const std::string& msg) {
  const auto& n = c.g.graph.node(c.node);
  c.errors.push_back({c.g.path, c.g.node_line(c.node, c.field),
                      "node '" + n.name() + "': " + what + " '" + path + "' " + msg});
}

bool exists(Ctx& c, const std::string& what, const std::string& path) {
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return true;
  add(c, what, path, fs::exists(path, ec) ? "is not a regular file" : "does not exist");
  return false;
}

void check_plan(Ctx& c, const std::string& prefix, const Message& m) {
  const auto* d = m.GetDescriptor();
  const auto* r = m.GetReflection();
  const std::string file = r->GetString(m, d->FindFieldByName("file"));
  if (file.empty()) return;
  const std::string path = resolve(c.g, file);
  if (!exists(c, prefix + ".file", path)) return;
  std::vector<std::string> layers;
  for (int i = 0; i < r->FieldSize(m, d->FindFieldByName("layers")); ++i)
    layers.push_back(r->GetRepeatedString(m, d->FindFieldByName("layers"), i));
  try {
    fploc::PlanLoadOptions o;
    o.layer_globs = layers;
    o.units_override = r->GetString(m, d->FindFieldByName("units"));
    o.quiet = true;
    const auto plan = fploc::load_floor_plan(path, o);
    if (plan.elements.empty()) add(c, prefix + ".file", path, "has no elements (layers?)");
  } catch (const std::exception& e) {
    add(c, prefix + ".file", path, std::string("does not load: ") + e.what());
  }
}

void check_pcap(Ctx& c, const std::string& what, const std::string& path) {
  if (!exists(c, what, path)) return;
  std::ifstream in(path, std::ios::binary);
  uint32_t magic = 0;
  in.read(reinterpret_cast<char*>(&magic), 4);
  // classic pcap (us/ns, either byte order) or pcapng (section header block)
  const std::set<uint32_t> ok{0xa1b2c3d4, 0xd4c3b2a1, 0xa1b23c4d, 0x4d3cb2a1, 0x0a0d0d0a};
  if (!in || !ok.count(magic)) add(c, what, path, "is not a pcap/pcapng capture (bad magic number)");
}

// Option fields that name a file a node writes: `*_out` (resolved against the graph's folder), the pose
// logger's files, `stats_file` and `out_*` (opened as given: relative to the working directory).
enum class Written { kNo, kGraphRelative, kCwdRelative };
Written written_kind(const google::protobuf::Descriptor* d, const FieldDescriptor* f) {
  if (f->cpp_type() != FieldDescriptor::CPPTYPE_STRING || f->is_repeated()) return Written::kNo;
  const std::string& n = f->name();
  if (n.size() > 4 && n.compare(n.size() - 4, 4, "_out") == 0) return Written::kGraphRelative;
  if (n == "stats_file" || n.rfind("out_", 0) == 0) return Written::kCwdRelative;  // out_json, out_dxf (plan_diff)
  if (d->full_name() == "fploc.PoseLoggerOptions" && (n == "file" || n == "uncertainty_file" || n == "floor_file"))
    return Written::kCwdRelative;
  return Written::kNo;
}

// A file a node will write: its folder must exist (the node cannot create the file otherwise and fails at set-up).
void check_output_folder(Ctx& c, const std::string& what, const std::string& path) {
  std::error_code ec;
  const fs::path dir = fs::absolute(fs::path(path), ec).parent_path();
  if (dir.empty() || fs::is_directory(dir, ec)) return;
  add(c, what, path, "cannot be written: its folder '" + dir.string() + "' " +
                         (fs::exists(dir, ec) ? "is not a folder" : "does not exist"));
}

void walk(Ctx& c, const std::string& prefix, const Message& m) {
  const auto* d = m.GetDescriptor();
  const auto* r = m.GetReflection();
  if (d->full_name() == "fploc.PlanSource") return check_plan(c, prefix, m);
  for (int i = 0; i < d->field_count(); ++i) {
    const FieldDescriptor* f = d->field(i);
    const std::string name = prefix + "." + f->name();
    if (f->is_repeated()) {
      if (f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE)
        for (int k = 0; k < r->FieldSize(m, f); ++k) walk(c, name, r->GetRepeatedMessage(m, f, k));
      continue;
    }
    if (f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) {
      if (r->HasField(m, f)) walk(c, name, r->GetMessage(m, f));
      continue;
    }
    if (f->cpp_type() != FieldDescriptor::CPPTYPE_STRING) continue;
    const std::string v = r->GetString(m, f);
    if (v.empty()) continue;
    const std::string path = resolve(c.g, v);
    if (const Written w = written_kind(d, f); w != Written::kNo) {
      if (!c.remote) check_output_folder(c, name, w == Written::kGraphRelative ? path : v);
      continue;
    }
    if (f->name() == "metadata") {
      if (c.written.count(path)) continue;  // written by another node when the graph runs
      const auto* host = d->FindFieldByName("sensor_hostname");
      std::error_code ec;
      if (host && !r->GetString(m, host).empty() && !fs::exists(path, ec)) continue;  // fetched, then cached
      if (!exists(c, name, path)) continue;
      try {
        fploc::os1::load_metadata(path);
      } catch (const std::exception& e) {
        add(c, name, path, std::string("does not parse: ") + e.what());
      }
    } else if (f->name() == "pcap") {
      check_pcap(c, name, path);
    } else if (d->full_name() == "fploc.DashboardOptions" && f->name() == "graph") {
      if (!exists(c, name, path)) continue;
      fploc::rt::LoadedGraph sub;
      std::vector<fploc::rt::GraphError> errs;
      if (!fploc::rt::load_graph(path, sub, errs))
        add(c, name, path, "does not parse: " + (errs.empty() ? std::string("?") : errs.front().str()));
    }
  }
}

// Files written by nodes at run time (so a reader of the same file is not an error).
void collect_written(const Message& m, const fploc::rt::LoadedGraph& g, std::set<std::string>& out) {
  const auto* d = m.GetDescriptor();
  const auto* r = m.GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const FieldDescriptor* f = d->field(i);
    if (f->is_repeated()) continue;
    if (f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE && r->HasField(m, f))
      collect_written(r->GetMessage(m, f), g, out);
    else if (f->cpp_type() == FieldDescriptor::CPPTYPE_STRING && f->name().size() > 4 &&
             f->name().compare(f->name().size() - 4, 4, "_out") == 0 && !r->GetString(m, f).empty())
      out.insert(resolve(g, r->GetString(m, f)));
  }
}

}  // namespace

void check_option_files(const fploc::rt::LoadedGraph& g, std::vector<fploc::rt::GraphError>& errors, bool skip_remote) {
  Ctx c{g, errors, {}, 0, ""};
  for (int i = 0; i < g.graph.node_size(); ++i) {
    auto opts = fploc::rt::node_options(g.graph.node(i));
    if (opts && !g.graph.node(i).disabled()) collect_written(*opts, g, c.written);
  }
  for (int i = 0; i < g.graph.node_size(); ++i) {
    const auto& n = g.graph.node(i);
    if (n.disabled() || (skip_remote && !n.host().empty())) continue;
    auto opts = fploc::rt::node_options(n);
    if (!opts) continue;
    c.node = i;
    c.remote = !n.host().empty();
    c.field = fploc::rt::node_options_field(n);
    walk(c, c.field, *opts);
  }
}

namespace {
// 1-based line of `path` ("wheel.seed") inside node `i`'s options block, else of the block, else of the node.
int option_line(const fploc::rt::LoadedGraph& g, int i, const std::string& path) {
  const std::string block = fploc::rt::node_options_field(g.graph.node(i));
  int line = g.node_line(i, block);
  const auto* node_field = fploc::Graph::descriptor()->FindFieldByName("node");
  const auto* tree = g.tree ? g.tree->GetTreeForNested(node_field, i) : nullptr;
  const FieldDescriptor* f = fploc::Node::descriptor()->FindFieldByName(block);
  if (tree && f) tree = tree->GetTreeForNested(f, -1);
  const google::protobuf::Descriptor* d = f ? f->message_type() : nullptr;
  size_t start = 0;
  while (tree && d && start <= path.size()) {
    const size_t dot = path.find('.', start);
    const std::string part = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    const FieldDescriptor* sub = d->FindFieldByName(part);
    if (!sub || sub->is_repeated()) break;
    const auto loc = tree->GetLocation(sub, -1);
    if (loc.line < 0) break;
    line = loc.line + 1;
    if (dot == std::string::npos) break;
    tree = tree->GetTreeForNested(sub, -1);
    d = sub->message_type();
    start = dot + 1;
  }
  return line;
}
}  // namespace

void check_option_values(const fploc::rt::LoadedGraph& g, std::vector<fploc::rt::GraphError>& errors) {
  for (int i = 0; i < g.graph.node_size(); ++i) {
    const auto& n = g.graph.node(i);
    if (n.disabled()) continue;
    auto opts = fploc::rt::node_options(n);
    if (!opts) continue;
    try {
      fploc::config::check_options(*opts);
      fploc::config::check_plan_required(*opts);
    } catch (const fploc::config::OptionError& e) {
      errors.push_back({g.path, option_line(g, i, e.field), "node '" + n.name() + "': " + e.what()});
    } catch (const std::exception& e) {
      errors.push_back({g.path, option_line(g, i, ""), "node '" + n.name() + "': " + e.what()});
    }
  }
}

}  // namespace fploc::launch
