#include "fploc/runtime/graph.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/json_util.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <type_traits>

namespace fploc::rt {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::TextFormat;

std::string GraphError::str() const {
  std::ostringstream s;
  s << file;
  if (line > 0) s << ":" << line;
  s << ": " << message;
  return s.str();
}

namespace {

class Collector : public google::protobuf::io::ErrorCollector {
 public:
  Collector(std::string file, std::vector<GraphError>& errors) : file_(std::move(file)), errors_(errors) {}
  void AddError(int line, google::protobuf::io::ColumnNumber col, const std::string& msg) override {
    errors_.push_back({file_, line + 1, msg});
    ++count;
  }
  void AddWarning(int line, google::protobuf::io::ColumnNumber col, const std::string& msg) override {
    // With AllowUnknownField(true) the parser reports unknown fields as warnings and carries on; for a
    // graph they are errors (a misspelt option must never be silently ignored).
    if (msg.find("no field named") != std::string::npos || msg.find("unknown") != std::string::npos) {
      errors_.push_back({file_, line + 1, msg + " (misspelt or unknown field)"});
      ++count;
    }
  }
  int count = 0;

 private:
  std::string file_;
  std::vector<GraphError>& errors_;
};

// Every field value of m that is not a message (nested and repeated ones too): fn(owner, field, k, path, line) with
// k the index in a repeated field (0 otherwise), path "a.b[2].c" and the field's line when the parse tree has it
// (else `line`). M: Message or const Message (nested messages are then reached for writing or for reading).
template <class M, class Fn>
void for_each_value(M& m, const std::string& prefix, const TextFormat::ParseInfoTree* tree, int line, Fn&& fn) {
  const auto* r = m.GetReflection();
  std::vector<const FieldDescriptor*> fields;
  r->ListFields(m, &fields);
  for (const auto* f : fields) {
    const int n = f->is_repeated() ? r->FieldSize(m, f) : 1;
    for (int k = 0; k < n; ++k) {
      const int index = f->is_repeated() ? k : -1;
      const std::string path = prefix + f->name() + (f->is_repeated() ? "[" + std::to_string(k) + "]" : "");
      int at = line;
      if (tree) {
        const auto loc = tree->GetLocation(f, index);
        if (loc.line >= 0) at = loc.line + 1;
      }
      if (f->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) {
        fn(m, f, k, path, at);
        continue;
      }
      const TextFormat::ParseInfoTree* nested = tree ? tree->GetTreeForNested(f, index) : nullptr;
      if constexpr (std::is_const_v<M>)
        for_each_value(f->is_repeated() ? r->GetRepeatedMessage(m, f, k) : r->GetMessage(m, f), path + ".", nested, at, fn);
      else
        for_each_value(f->is_repeated() ? *r->MutableRepeatedMessage(&m, f, k) : *r->MutableMessage(&m, f), path + ".",
                       nested, at, fn);
    }
  }
}

// Float and double fields (nested and repeated ones too) that are NaN or infinite: "path is nan", with the
// field's line when the parse tree has it (else `line`).
void non_finite(const Message& m, const std::string& prefix, const TextFormat::ParseInfoTree* tree, int line,
                std::vector<std::pair<std::string, int>>& out) {
  for_each_value(m, prefix, tree, line, [&](const Message& o, const FieldDescriptor* f, int k, const std::string& path, int at) {
    if (f->cpp_type() != FieldDescriptor::CPPTYPE_DOUBLE && f->cpp_type() != FieldDescriptor::CPPTYPE_FLOAT) return;
    const auto* r = o.GetReflection();
    const double v = f->cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE
                         ? (f->is_repeated() ? r->GetRepeatedDouble(o, f, k) : r->GetDouble(o, f))
                         : (f->is_repeated() ? r->GetRepeatedFloat(o, f, k) : r->GetFloat(o, f));
    if (!std::isfinite(v)) out.push_back({path + " is " + (std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf"), at});
  });
}

// String option values (nested and repeated ones too) with ${NAME} or ${NAME:-default}: the environment's value
// (the default when NAME is unset or empty), so a graph can leave e.g. its output folder to the user
// (graphs/demo.pbtxt: ${FPLOC_DEMO_DIR:-/tmp}). A NAME unset with no default: "path: ..." in `out`.
void expand_env(Message& m, const std::string& prefix, const TextFormat::ParseInfoTree* tree, int line,
                std::vector<std::pair<std::string, int>>& out) {
  for_each_value(m, prefix, tree, line, [&](Message& o, const FieldDescriptor* f, int k, const std::string& path, int at) {
    if (f->cpp_type() != FieldDescriptor::CPPTYPE_STRING || f->type() == FieldDescriptor::TYPE_BYTES) return;
    const auto* r = o.GetReflection();
    const std::string v = f->is_repeated() ? r->GetRepeatedString(o, f, k) : r->GetString(o, f);
    if (v.find("${") == std::string::npos) return;
    std::string res;
    size_t i = 0;
    bool ok = true;
    while (i < v.size()) {
      const size_t b = v.find("${", i);
      const size_t e = b == std::string::npos ? b : v.find('}', b);
      if (b == std::string::npos || e == std::string::npos) {
        res += v.substr(i);
        break;
      }
      res += v.substr(i, b - i);
      const std::string expr = v.substr(b + 2, e - b - 2);
      const size_t dflt = expr.find(":-");
      const std::string name = expr.substr(0, dflt);
      const char* env = std::getenv(name.c_str());
      if (env && *env) res += env;
      else if (dflt != std::string::npos) res += expr.substr(dflt + 2);
      else {
        out.push_back({path + ": environment variable " + name + " is not set (write ${" + name + ":-DEFAULT} for a default)", at});
        ok = false;
      }
      i = e + 1;
    }
    if (!ok) return;
    if (f->is_repeated()) r->SetRepeatedString(&o, f, k, res);
    else r->SetString(&o, f, res);
  });
}

}  // namespace

bool parse_graph_text(const std::string& text, const std::string& name, LoadedGraph& out,
                      std::vector<GraphError>& errors) {
  out.path = name;
  out.dir = std::filesystem::absolute(std::filesystem::path(name)).parent_path().string();
  out.tree = std::make_shared<TextFormat::ParseInfoTree>();
  Collector collector(name, errors);
  TextFormat::Parser parser;
  parser.RecordErrorsTo(&collector);
  parser.WriteLocationsTo(out.tree.get());
  parser.AllowUnknownField(true);
  const bool ok = parser.ParseFromString(text, &out.graph);
  if (!ok) return false;
  // A misspelt field (counted by the collector) still leaves the rest of the graph parsed, and the launcher's
  // --check goes on checking it: its ${NAME:-default} values are expanded all the same (they were not, and
  // --check said e.g. "pose_logger.file '${FPLOC_DEMO_DIR:-/tmp}/...' cannot be written" beside the one real error).
  const size_t before = errors.size() - collector.count;
  // NaN and inf parse as numbers; in an option they are never meant (a NaN initial pose).
  std::vector<std::pair<std::string, int>> bad;
  const auto* node_field = fploc::Graph::descriptor()->FindFieldByName("node");
  for (int i = 0; i < out.graph.node_size(); ++i) {
    const auto& n = out.graph.node(i);
    bad.clear();
    non_finite(n, "", out.tree->GetTreeForNested(node_field, i), out.tree->GetLocation(node_field, i).line + 1, bad);
    for (const auto& [what, line] : bad) errors.push_back({name, line, "node '" + n.name() + "': " + what + " (not a finite number)"});
    bad.clear();
    expand_env(*out.graph.mutable_node(i), "", out.tree->GetTreeForNested(node_field, i),
               out.tree->GetLocation(node_field, i).line + 1, bad);
    for (const auto& [what, line] : bad) errors.push_back({name, line, "node '" + n.name() + "': " + what});
  }
  fploc::Graph rest = out.graph;  // the graph's own fields
  rest.clear_node();
  bad.clear();
  non_finite(rest, "", out.tree.get(), 0, bad);
  for (const auto& [what, line] : bad) errors.push_back({name, line, what + " (not a finite number)"});
  return errors.size() == before;
}

bool load_graph(const std::string& path, LoadedGraph& out, std::vector<GraphError>& errors) {
  std::ifstream in(path);
  if (!in) {
    errors.push_back({path, 0, "cannot open graph file"});
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_graph_text(ss.str(), path, out, errors);
}

int LoadedGraph::node_line(int node_index, const std::string& field, int field_index) const {
  const auto* gd = fploc::Graph::descriptor();
  const auto* node_field = gd->FindFieldByName("node");
  const auto loc = tree->GetLocation(node_field, node_index);
  if (field.empty()) return loc.line + 1;
  auto* sub = tree->GetTreeForNested(node_field, node_index);
  if (!sub) return loc.line + 1;
  const auto* f = fploc::Node::descriptor()->FindFieldByName(field);
  if (!f) return loc.line + 1;
  const auto l = sub->GetLocation(f, f->is_repeated() ? std::max(field_index, 0) : -1);
  return l.line >= 0 ? l.line + 1 : loc.line + 1;
}

std::string node_options_field(const fploc::Node& node) {
  const auto* oneof = fploc::Node::descriptor()->FindOneofByName("options");
  const auto* f = node.GetReflection()->GetOneofFieldDescriptor(node, oneof);
  return f ? f->name() : "";
}

std::unique_ptr<Message> node_options(const fploc::Node& node) {
  const auto* oneof = fploc::Node::descriptor()->FindOneofByName("options");
  const auto* f = node.GetReflection()->GetOneofFieldDescriptor(node, oneof);
  if (!f) return nullptr;
  const Message& m = node.GetReflection()->GetMessage(node, f);
  std::unique_ptr<Message> copy(m.New());
  copy->CopyFrom(m);
  return copy;
}

std::unique_ptr<Message> default_options(const std::string& field) {
  const auto* f = fploc::Node::descriptor()->FindFieldByName(field);
  if (!f || !f->containing_oneof() || f->type() != FieldDescriptor::TYPE_MESSAGE) return nullptr;
  fploc::Node n;
  const Message& m = n.GetReflection()->GetMessage(n, f);
  return std::unique_ptr<Message>(m.New());
}

bool apply_overrides(Message& opts, const std::vector<std::string>& overrides, std::string& error) {
  for (const auto& kv : overrides) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) {
      error = "override '" + kv + "': expected field=value";
      return false;
    }
    const std::string path = kv.substr(0, eq), value = kv.substr(eq + 1);
    // Walk "a.b.c" to build nested text: a { b { c: value } }.
    std::vector<std::string> parts;
    std::stringstream ps(path);
    for (std::string p; std::getline(ps, p, '.');) parts.push_back(p);
    const Descriptor* d = opts.GetDescriptor();
    const FieldDescriptor* f = nullptr;
    for (size_t i = 0; i < parts.size(); ++i) {
      f = d ? d->FindFieldByName(parts[i]) : nullptr;
      if (!f) {
        error = "override '" + kv + "': " + opts.GetDescriptor()->full_name() + " has no field '" + path + "'";
        return false;
      }
      if (i + 1 < parts.size()) d = f->message_type();
    }
    std::string v = value;
    if (f->type() == FieldDescriptor::TYPE_STRING && (v.empty() || v.front() != '"')) {
      std::string q = "\"";
      for (char c : v) {
        if (c == '"' || c == '\\') q += '\\';
        q += c;
      }
      v = q + "\"";
    }
    std::string text;
    for (size_t i = 0; i + 1 < parts.size(); ++i) text += parts[i] + " { ";
    text += parts.back() + ": " + v;
    for (size_t i = 0; i + 1 < parts.size(); ++i) text += " }";
    std::vector<GraphError> errs;
    Collector c("--set", errs);
    TextFormat::Parser parser;
    parser.RecordErrorsTo(&c);
    // Merged into a copy: a value that is not finite (nan, inf parse as numbers) leaves the options as they were.
    std::unique_ptr<Message> merged(opts.New());
    merged->CopyFrom(opts);
    if (!parser.MergeFromString(text, merged.get()) || c.count) {
      error = "override '" + kv + "': " + (errs.empty() ? std::string("cannot parse value") : errs.front().message);
      return false;
    }
    std::vector<std::pair<std::string, int>> before, after;
    non_finite(opts, "", nullptr, 0, before);
    non_finite(*merged, "", nullptr, 0, after);
    for (const auto& b : after)
      if (std::find(before.begin(), before.end(), b) == before.end()) {
        error = "override '" + kv + "': " + b.first + " (not a finite number)";
        return false;
      }
    opts.CopyFrom(*merged);
  }
  return true;
}

namespace {
nlohmann::json describe(const Descriptor* d, int depth) {
  nlohmann::json j;
  j["type"] = d->full_name();
  auto& fields = j["fields"] = nlohmann::json::array();
  for (int i = 0; i < d->field_count(); ++i) {
    const auto* f = d->field(i);
    nlohmann::json fj{{"name", f->name()}, {"type", f->type_name()}, {"repeated", f->is_repeated()}};
    if (f->message_type() && depth < 4) fj["message"] = describe(f->message_type(), depth + 1);
    if (f->enum_type()) {
      auto& vals = fj["values"] = nlohmann::json::array();
      for (int k = 0; k < f->enum_type()->value_count(); ++k) vals.push_back(f->enum_type()->value(k)->name());
    }
    fields.push_back(fj);
  }
  return j;
}
}  // namespace

bool is_path_option(const std::string& field) {
  // The string options the nodes read or write as files (Context::resolve_path, or opened as given).
  static const std::set<std::string> kPaths = {"file",         "metadata",    "pcap",       "world",
                                               "metadata_out", "web_root",    "graph",      "serial_device",
                                               "stats_file",   "out_json",    "out_dxf",    "uncertainty_file",
                                               "floor_file"};
  return kPaths.count(field) > 0;
}

std::string command_line_path_override(const std::string& set, const std::string& cwd) {
  const auto eq = set.find('=');
  if (eq == std::string::npos) return set;
  const std::string path = set.substr(0, eq), value = set.substr(eq + 1);
  const auto dot = path.rfind('.');
  const std::string leaf = dot == std::string::npos ? path : path.substr(dot + 1);
  if (value.empty() || value.front() == '"' || !is_path_option(leaf) || std::filesystem::path(value).is_absolute())
    return set;
  return path + "=" + (std::filesystem::path(cwd) / value).lexically_normal().string();
}

bool apply_node_overrides(fploc::Graph& graph, const std::vector<std::string>& sets,
                          const std::function<std::string(const fploc::Node&)>& default_field, std::string& error) {
  // A path given on the command line is relative to the working directory, as every other path of the command
  // (a graph's own paths are relative to its folder: `--set matcher.plan.file=my.dxf` looked in graphs/).
  std::error_code ec;
  const std::string cwd = std::filesystem::current_path(ec).string();
  for (const auto& given : sets) {
    const std::string s = ec ? given : command_line_path_override(given, cwd);
    const auto dot = s.find('.');
    fploc::Node* target = nullptr;
    for (int i = 0; dot != std::string::npos && i < graph.node_size(); ++i)
      if (graph.node(i).name() == s.substr(0, dot)) target = graph.mutable_node(i);
    if (!target) {
      error = "--set " + given + ": expected NODE.field=value with a node of the graph";
      return false;
    }
    std::string field = node_options_field(*target);
    if (field.empty() && default_field) field = default_field(*target);
    const FieldDescriptor* fd = field.empty() ? nullptr : fploc::Node::descriptor()->FindFieldByName(field);
    if (!fd || !fd->message_type()) {
      error = "--set " + given + ": node '" + target->name() + "' takes no options";
      return false;
    }
    Message* opts = target->GetReflection()->MutableMessage(target, fd);
    if (!apply_overrides(*opts, {s.substr(dot + 1)}, error)) {
      error = "--set " + given + " (node '" + target->name() + "'): " + error;
      return false;
    }
  }
  return true;
}

std::string describe_message_json(const Descriptor* d) { return describe(d, 0).dump(); }

}  // namespace fploc::rt
