#include "control.h"

namespace fploc::launch {
namespace {
const fploc::Node& graph_node(const fploc::Graph& g, const std::string& name) {
  for (const auto& n : g.node())
    if (n.name() == name) return n;
  static const fploc::Node empty;
  return empty;
}
ControlDecision reject(const std::string& node, std::string why) {
  ControlDecision d;
  d.node = node;
  d.error = std::move(why);
  return d;
}
}  // namespace

ControlDecision decide_control(const fploc::node_command_t& m, const ProcessEntry* c, const fploc::Graph& graph,
                               const fploc::rt::ValidateHooks& hooks) {
  if (!graph.control_token().empty() && m.token != graph.control_token()) return reject(m.node, "wrong control token");
  if (!c) {
    std::string names;  // the graph's nodes, so a typo is easy to fix
    for (const auto& n : graph.node())
      if (!n.disabled()) names += (names.empty() ? "" : ", ") + n.name();
    return reject(m.node, "no running node named '" + m.node + "' (nodes: " + (names.empty() ? "none" : names) + ")");
  }
  ControlDecision d;
  d.node = m.node;
  if (m.action == "stop") {
    d.kind = ControlDecision::Stop;
    return d;
  }
  if (m.action != "restart" && m.action != "start")
    return reject(m.node, "unknown action '" + m.action + "' (restart, stop, start)");
  ProcessEntry e = *c;
  if (!m.executable.empty() && m.executable != c->exe_name) {
    const std::string path = hooks.resolve(m.executable);
    if (path.empty()) return reject(m.node, "executable '" + m.executable + "' not found");
    auto desc = hooks.describe(path);
    if (!desc.error.empty()) return reject(m.node, desc.error);
    const std::string graph_field = fploc::rt::node_options_field(graph_node(graph, c->name));
    if (desc.describable && !graph_field.empty() && graph_field != desc.spec.options_field)
      return reject(m.node, "'" + m.executable + "' takes options '" + desc.spec.options_field +
                                "' but the graph gives '" + graph_field + "'");
    // The swapped-in module must offer the ports the graph maps, with the same LCM types as before.
    if (desc.describable && c->fploc_node) {
      for (const auto& old_p : c->spec.ports) {
        const fploc::rt::PortSpec* np = nullptr;
        for (const auto& p : desc.spec.ports)
          if (p.name == old_p.name && p.output == old_p.output) np = &p;
        if (!np)
          return reject(m.node, "'" + m.executable + "' has no " + (old_p.output ? "output" : "input") + " port '" +
                                    old_p.name + "' (the running " + c->exe_name + " has)");
        if (np->lcm_type != old_p.lcm_type)
          return reject(m.node, "'" + m.executable + "' port '" + np->name + "' is " + np->lcm_type +
                                    ", the graph's channel carries " + old_p.lcm_type);
      }
    }
    e.exe_name = m.executable;
    e.exe_path = path;
    e.spec = desc.spec;
    e.fploc_node = desc.describable;
    e.options_field = desc.spec.options_field;
  }
  std::vector<std::string> sets(m.set.begin(), m.set.end());
  if (!sets.empty()) {
    if (!e.fploc_node) return reject(m.node, "--set needs an fploc node");
    auto opts = fploc::rt::node_options(graph_node(graph, c->name));
    if (!opts) opts = fploc::rt::default_options(e.options_field);
    if (!opts) return reject(m.node, "node takes no options");
    std::string err;
    auto all = c->sets;
    all.insert(all.end(), sets.begin(), sets.end());
    if (!fploc::rt::apply_overrides(*opts, all, err)) return reject(m.node, err);
    sets = all;
  } else {
    sets = c->sets;
  }
  if (e.exe_name != c->exe_name) sets = std::vector<std::string>(m.set.begin(), m.set.end());
  e.sets = sets;
  d.kind = ControlDecision::Restart;
  d.entry = std::move(e);
  return d;
}

}  // namespace fploc::launch
