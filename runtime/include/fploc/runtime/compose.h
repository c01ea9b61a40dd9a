// Several nodes of a graph in one process over one LCM instance (memq:// for lock-step replay).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "fploc/runtime/bus.h"
#include "fploc/runtime/graph.h"
#include "fploc/runtime/node.h"

namespace fploc::rt {

struct ComposedNode {
  std::string name;
  std::unique_ptr<Context> ctx;
  std::unique_ptr<Node> node;
};

class Composition {
 public:
  // Instantiates every enabled node of the graph whose type is linked into this process. Nodes
  // listed in `skip` (by name) are left out. Throws std::runtime_error naming the node on failure.
  Composition(const LoadedGraph& graph, Bus& bus, const std::vector<std::string>& skip = {});
  // Dispatches queued messages until none is left (memq: deterministic, depth-first FIFO).
  void drain();
  void shutdown();
  std::vector<ComposedNode>& nodes() { return nodes_; }
  // Channels that some node subscribes to but no composed node publishes (the log must feed these).
  std::vector<std::string> external_inputs() const;

 private:
  Bus& bus_;
  std::vector<ComposedNode> nodes_;
};

}  // namespace fploc::rt
