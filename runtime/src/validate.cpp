#include "fploc/runtime/validate.h"

#include "fploc/runtime/subprocess.h"
#include "fploc/runtime/robot.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "fploc/runtime/bus.h"

namespace fploc::rt {

std::string spec_json(const NodeSpec& spec) {
  nlohmann::json j;
  j["type"] = spec.type;
  j["description"] = spec.description;
  j["options_field"] = spec.options_field;
  auto& ports = j["ports"] = nlohmann::json::array();
  for (const auto& p : spec.ports) {
    ports.push_back({{"name", p.name},
                     {"direction", p.output ? "output" : "input"},
                     {"lcm_type", p.lcm_type},
                     {"default_channel", p.default_channel}});
    if (!p.output && p.queue == Queue::kLatest) ports.back()["queue"] = "latest";  // new key, only where set
  }
  auto d = default_options(spec.options_field);
  j["options"] = d ? nlohmann::json::parse(describe_message_json(d->GetDescriptor())) : nlohmann::json();
  return j.dump();
}

NodeSpec parse_spec_json(const std::string& text) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("--describe did not print JSON: ") + e.what());
  }
  NodeSpec s;
  try {
    s.type = j.at("type").get<std::string>();
    s.options_field = j.value("options_field", "");
    s.description = j.value("description", "");
    for (const auto& p : j.at("ports")) {
      PortSpec ps;
      ps.name = p.at("name").get<std::string>();
      ps.output = p.at("direction").get<std::string>() == "output";
      ps.lcm_type = p.at("lcm_type").get<std::string>();
      ps.default_channel = p.value("default_channel", "");
      ps.queue = p.value("queue", "") == "latest" ? Queue::kLatest : Queue::kAll;
      s.ports.push_back(ps);
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("--describe JSON lacks a field: ") + e.what());
  }
  return s;
}

static bool is_exec_file(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
}

std::string resolve_executable(const std::string& exe, const std::string& bin_dir) {
  if (exe.empty()) return "";
  if (exe.find('/') != std::string::npos)
    return is_exec_file(exe) ? std::filesystem::absolute(exe).lexically_normal().string() : "";
  if (!bin_dir.empty()) {
    const std::string p = bin_dir + "/" + exe;
    if (is_exec_file(p)) return p;
  }
  const char* path = getenv("PATH");
  std::stringstream ss(path ? path : "");
  for (std::string dir; std::getline(ss, dir, ':');) {
    if (dir.empty()) continue;
    const std::string p = dir + "/" + exe;
    if (is_exec_file(p)) return p;
  }
  return "";
}

std::string self_bin_dir() {
  std::error_code ec;
  auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : p.parent_path().string();
}

// Runs argv, returns its stdout; false on failure, timeout or non-zero exit.
static bool run_capture(const std::vector<std::string>& args, double timeout_s, std::string& out, std::string& err) {
  RunOptions o;
  o.timeout_s = timeout_s;
  RunResult r = run_program(args, o);
  out = std::move(r.output);
  err = r.problem;
  return r.exit_code == 0;
}

DescribeResult describe_executable(const std::string& resolved_path) {
  DescribeResult r;
  const std::string base = std::filesystem::path(resolved_path).filename().string();
  if (base.rfind("fploc-", 0) != 0) return r;  // a foreign program: nothing to ask
  r.describable = true;
  std::string out, err;
  if (!run_capture({resolved_path, "--describe"}, 10.0, out, err)) {
    r.error = "'" + resolved_path + " --describe' failed (" + err + ")";
    return r;
  }
  try {
    r.spec = parse_spec_json(out);
  } catch (const std::exception& e) {
    r.error = "'" + resolved_path + "': " + e.what();
  }
  return r;
}

ValidateHooks default_hooks(const std::string& bin_dir) {
  ValidateHooks h;
  h.resolve = [bin_dir](const std::string& exe) { return resolve_executable(exe, bin_dir); };
  auto cache = std::make_shared<std::map<std::string, DescribeResult>>();
  h.describe = [cache](const std::string& path) {
    auto it = cache->find(path);
    if (it != cache->end()) return it->second;
    return (*cache)[path] = describe_executable(path);
  };
  return h;
}

namespace {
struct Endpoint {
  std::string node, port, type;  // type "" = unknown (foreign program)
  int line;
};

bool valid_name(const std::string& s) {
  for (char c : s)
    if (!(isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return !s.empty();
}
}  // namespace

bool validate_graph(const LoadedGraph& g, const ValidateHooks& hooks, std::vector<GraphError>& errors,
                    std::vector<ResolvedNode>* resolved) {
  const size_t before = errors.size();
  auto err = [&](int line, const std::string& msg) { errors.push_back({g.path, line, msg}); };
  std::map<std::string, int> names;
  std::map<std::string, std::vector<Endpoint>> producers, consumers;
  producers[kTelemetryChannel].push_back({"(every node)", "telemetry", "fploc.node_status_t", 0});
  const std::string control = g.graph.control_channel().empty() ? kControlChannel : g.graph.control_channel();
  producers[control].push_back({"(fploc node)", "control", "fploc.node_command_t", 0});
  producers[kInitialPoseChannel].push_back({"(fploc node initial-pose)", "initial_pose", "fploc.pose_t", 0});

  if (!valid_robot_name(g.graph.robot()))
    err(0, "robot '" + g.graph.robot() + "': letters, digits, '_' and '-' only (at most 32), it prefixes every channel");
  std::map<std::string, int> hosts;
  for (int h = 0; h < g.graph.host_size(); ++h) {
    const auto& host = g.graph.host(h);
    if (!valid_name(host.name())) err(0, "host " + std::to_string(h + 1) + ": name '" + host.name() + "' is not a valid name");
    else if (hosts.count(host.name())) err(0, "host '" + host.name() + "' is listed twice");
    hosts[host.name()] = h;
    if (host.address().empty()) err(0, "host '" + host.name() + "': address is empty");
  }
  for (int i = 0; i < g.graph.node_size(); ++i) {
    const auto& n = g.graph.node(i);
    if (!n.host().empty() && !hosts.count(n.host()))
      err(g.node_line(i, "host"), "node '" + n.name() + "': host '" + n.host() + "' is not one of the graph's hosts" +
                                      (hosts.empty() ? " (the graph lists none)" : ""));
  }
  if (g.graph.lcm_ttl() < 0 || g.graph.lcm_ttl() > 255) err(0, "lcm_ttl must be 0..255");

  bool unknown_ports = false;  // an enabled fploc node could not be described: it may be a missing producer
  for (int i = 0; i < g.graph.node_size(); ++i) {
    const auto& n = g.graph.node(i);
    const int line = g.node_line(i);
    const std::string who = "node '" + n.name() + "'";
    ResolvedNode rn;
    rn.index = i;
    if (n.name().empty()) {
      err(line, "node has no name");
    } else if (!valid_name(n.name())) {
      err(g.node_line(i, "name"), who + ": names use letters, digits, '_', '-' and '.' only");
    } else if (auto it = names.find(n.name()); it != names.end()) {
      err(g.node_line(i, "name"),
          "duplicate node name '" + n.name() + "' (first defined at line " + std::to_string(it->second) + ")");
    } else {
      names[n.name()] = line;
    }
    // Executable and what it declares.
    if (n.executable().empty()) {
      if (!n.disabled()) err(line, who + ": no executable");
    } else {
      rn.executable = hooks.resolve ? hooks.resolve(n.executable()) : n.executable();
      if (rn.executable.empty()) {
        if (!n.disabled())
          err(g.node_line(i, "executable"),
              who + ": executable '" + n.executable() + "' not found (build bin/ or PATH)");
      } else if (hooks.describe) {
        rn.desc = hooks.describe(rn.executable);
        if (!rn.desc.error.empty()) err(g.node_line(i, "executable"), who + ": " + rn.desc.error);
      }
    }
    const bool typed = rn.desc.describable && rn.desc.error.empty();
    if (!n.disabled() && !n.executable().empty() && (rn.executable.empty() || !rn.desc.error.empty()))
      unknown_ports = true;
    const std::string opt_field = node_options_field(n);
    if (typed && !opt_field.empty() && opt_field != rn.desc.spec.options_field) {
      err(g.node_line(i, opt_field),
          who + ": options field '" + opt_field + "' does not match " + n.executable() + ", which takes " +
              (rn.desc.spec.options_field.empty() ? std::string("no options")
                                                  : "'" + rn.desc.spec.options_field + "'"));
    }
    // Restart policy and heartbeat.
    const auto& rp = n.restart();
    if (rp.max_restarts() < 0 || rp.window_s() < 0 || rp.backoff_initial_s() < 0 || rp.backoff_max_s() < 0 ||
        rp.backoff_factor() < 0 || (rp.backoff_factor() > 0 && rp.backoff_factor() < 1))
      err(g.node_line(i, "restart"), who + ": restart policy values must be >= 0 (backoff_factor >= 1)");
    if (n.heartbeat_timeout_s() < 0) err(g.node_line(i, "heartbeat_timeout_s"), who + ": heartbeat_timeout_s < 0");

    // Ports: graph mappings must name ports of the executable; every declared port gets a channel.
    std::set<std::string> mapped_in, mapped_out;
    auto check_map = [&](const google::protobuf::RepeatedPtrField<fploc::Port>& ports, const char* field, bool output) {
      for (int k = 0; k < ports.size(); ++k) {
        const auto& p = ports[k];
        const int pl = g.node_line(i, field, k);
        auto& seen = output ? mapped_out : mapped_in;
        if (p.port().empty()) {
          err(pl, who + ": " + field + " needs a port name");
          continue;
        }
        if (!seen.insert(p.port()).second) err(pl, who + ": port '" + p.port() + "' mapped twice");
        if (output && p.queue() != fploc::Port::SPEC)
          err(pl, who + ": output port '" + p.port() + "' has a queue policy (queue applies to inputs only)");
        std::string type;
        if (typed) {
          const PortSpec* ps = nullptr;
          for (const auto& s : rn.desc.spec.ports)
            if (s.name == p.port() && s.output == output) ps = &s;
          if (!ps) {
            std::string have;
            for (const auto& s : rn.desc.spec.ports)
              if (s.output == output) have += (have.empty() ? "" : ", ") + s.name;
            err(pl, who + ": " + n.executable() + " has no " + field + " port '" + p.port() + "' (its " + field +
                        "s: " + (have.empty() ? "none" : have) + ")");
            continue;
          }
          type = ps->lcm_type;
        }
        if ((n.disabled() && !output) || p.channel().empty()) continue;  // "" = not connected
        (output ? producers : consumers)[p.channel()].push_back({n.name(), p.port(), type, pl});
      }
    };
    check_map(n.input(), "input", false);
    check_map(n.output(), "output", true);
    if (typed) {
      for (const auto& s : rn.desc.spec.ports) {
        if ((s.output ? mapped_out : mapped_in).count(s.name)) continue;
        if ((n.disabled() && !s.output) || s.default_channel.empty()) continue;
        (s.output ? producers : consumers)[s.default_channel].push_back({n.name(), s.name, s.lcm_type, line});
      }
    }
    if (resolved) resolved->push_back(std::move(rn));
  }

  // Channels: every input has a producer; typed ends agree.
  for (const auto& [channel, cons] : consumers) {
    auto pit = producers.find(channel);
    for (const auto& c : cons) {
      if (pit == producers.end()) {
        if (unknown_ports) continue;  // reported once every executable is there (no cascades)
        // How to say "not connected" (a display-only input such as the dashboard's, an optional one).
        err(c.line, "node '" + c.node + "' input '" + c.port + "' on channel '" + channel +
                        "' has no producer (no node of the graph publishes it); if it is to stay unconnected: input { port: \"" +
                        c.port + "\" channel: \"\" }");
        continue;
      }
      for (const auto& p : pit->second) {
        if (!c.type.empty() && !p.type.empty() && c.type != p.type) {
          err(c.line, "channel '" + channel + "': node '" + c.node + "' input '" + c.port + "' expects " + c.type +
                          " but node '" + p.node + "' output '" + p.port + "' publishes " + p.type +
                          (p.line > 0 ? " (line " + std::to_string(p.line) + ")" : ""));
          break;
        }
      }
    }
  }
  for (const auto& [channel, prods] : producers) {
    for (size_t a = 1; a < prods.size(); ++a) {
      if (!prods[a].type.empty() && !prods[0].type.empty() && prods[a].type != prods[0].type)
        err(prods[a].line, "channel '" + channel + "': node '" + prods[a].node + "' publishes " + prods[a].type +
                               " but node '" + prods[0].node + "' publishes " + prods[0].type + " on it");
    }
  }
  std::stable_sort(errors.begin() + long(before), errors.end(),
                   [](const GraphError& a, const GraphError& b) { return a.line < b.line; });
  return errors.size() == before;
}

}  // namespace fploc::rt
