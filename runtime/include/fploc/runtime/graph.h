// Loading graph files (protobuf text format against proto/graph.proto) with source locations, so
// every problem is reported as `file:line: message`.
#pragma once
#include <google/protobuf/message.h>
#include <google/protobuf/text_format.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "graph.pb.h"

namespace fploc::rt {

struct GraphError {
  std::string file;
  int line = 0;  // 1-based, 0 = whole file
  std::string message;
  std::string str() const;
};

struct LoadedGraph {
  fploc::Graph graph;
  std::string path;  // as given
  std::string dir;   // folder of the file (relative option paths resolve here)
  std::shared_ptr<google::protobuf::TextFormat::ParseInfoTree> tree;
  // 1-based line of graph.node[i] (or of one of its fields when `field` is given).
  int node_line(int node_index, const std::string& field = "", int field_index = -1) const;
};

// Parses the file. Unknown or misspelt fields, wrong value types and syntax errors are all collected
// (parsing goes on past unknown fields so that every error is listed). Returns false on any error.
bool load_graph(const std::string& path, LoadedGraph& out, std::vector<GraphError>& errors);
bool parse_graph_text(const std::string& text, const std::string& name, LoadedGraph& out,
                      std::vector<GraphError>& errors);

// The node's options message (a copy of the set `options` oneof field), or nullptr when none is set.
std::unique_ptr<google::protobuf::Message> node_options(const fploc::Node& node);
// Name of the oneof field that is set ("" when none).
std::string node_options_field(const fploc::Node& node);
// Default instance of the options message for a field name of Node.options (nullptr if unknown).
std::unique_ptr<google::protobuf::Message> default_options(const std::string& field);

// Applies overrides "path.to.field=value" (text-format values; strings may be unquoted) to `opts`.
// Returns false and sets `error` naming the field when one does not exist or does not parse.
bool apply_overrides(google::protobuf::Message& opts, const std::vector<std::string>& overrides, std::string& error);

// Applies "NODE.path.to.field=value" overrides to the options of the graph's nodes (fploc launch/replay
// --set). `default_field(node)` names the options field of a node whose graph entry has no options block
// (from its executable's spec; "" = takes none). Returns false and sets `error` naming the override.
// A relative path given for a file option (is_path_option: plan.file, metadata, pcap, world, ...) is taken
// relative to the working directory, as any path on a command line (the graph's own are relative to its folder).
bool apply_node_overrides(fploc::Graph& graph, const std::vector<std::string>& sets,
                          const std::function<std::string(const fploc::Node&)>& default_field, std::string& error);

// The string option names that are files (the last component of an override's field path).
bool is_path_option(const std::string& field);
// "NODE.a.file=rel" -> "NODE.a.file=CWD/rel" for a path option with a relative value; anything else unchanged.
std::string command_line_path_override(const std::string& set, const std::string& cwd);

// JSON schema-ish description of a message type (fields, types, nested messages), for --describe.
std::string describe_message_json(const google::protobuf::Descriptor* d);

}  // namespace fploc::rt
