#include "hosts.h"

#include "fploc/runtime/subprocess.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <future>
#include <map>
#include <regex>
#include <set>
#include <sstream>

namespace fploc::launch {
namespace fs = std::filesystem;

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string HostPlan::root() const { return spec.fploc_root().empty() ? local_root : spec.fploc_root(); }

std::string HostPlan::bin() const {
  if (!spec.build_dir().empty()) return (fs::path(spec.build_dir()) / "bin").string();
  const auto rel = fs::path(local_bin).lexically_relative(local_root);
  if (!rel.empty() && rel.begin()->string() != "..") return (fs::path(root()) / rel).string();
  return (fs::path(root()) / "build" / "bin").string();
}

std::string HostPlan::map_path(const std::string& p) const {
  const fs::path abs = fs::absolute(p).lexically_normal();
  auto rel = abs.lexically_relative(local_bin);
  if (!rel.empty() && rel.begin()->string() != "..") return (fs::path(bin()) / rel).string();
  rel = abs.lexically_relative(local_root);
  if (!rel.empty() && rel.begin()->string() != "..") return (fs::path(root()) / rel).string();
  return abs.string();
}

std::vector<std::string> HostPlan::ssh_argv(const std::string& command, double connect_timeout_s) const {
  std::vector<std::string> a{"ssh", "-T", "-o", "BatchMode=yes", "-o", "ServerAliveInterval=1", "-o",
                             "ServerAliveCountMax=2", "-o", "ConnectTimeout=" + std::to_string(int(connect_timeout_s)),
                             "-o", "LogLevel=ERROR"};
  if (spec.port() > 0) a.insert(a.end(), {"-p", std::to_string(spec.port())});
  if (!spec.user().empty()) a.insert(a.end(), {"-l", spec.user()});
  for (const auto& o : spec.ssh_option()) a.insert(a.end(), {"-o", o});
  if (!control_path.empty()) a.insert(a.end(), {"-o", "ControlMaster=no", "-o", "ControlPath=" + control_path});
  a.push_back(spec.address());
  a.push_back("--");
  a.push_back(command);
  return a;
}

std::vector<std::string> HostPlan::master_argv() const {
  auto a = ssh_argv("true");
  a.resize(a.size() - 3);  // no address / "--" / command yet
  for (size_t k = 0; k + 1 < a.size(); ++k)
    if (a[k] == "-o" && a[k + 1] == "ControlMaster=no") a[k + 1] = "ControlMaster=yes";
  a.insert(a.end(), {"-o", "ControlPersist=no", "-N", spec.address()});
  return a;
}

std::vector<std::string> HostPlan::probe_argv(const std::string& command) const {
  HostPlan own = *this;
  own.control_path.clear();
  auto a = own.ssh_argv(command);
  // First, as ssh keeps an option's first value: a graph's own ssh_option ControlPath/ControlMaster cannot put the
  // probe on a shared connection (which can outlive a cut link and answer for a host that is away).
  a.insert(a.begin() + 1, {"-o", "ControlPath=none", "-o", "ControlMaster=no"});
  return a;
}

std::string HostPlan::unreachable(int rc, const std::string& out) const {
  const std::string who = spec.address() + (spec.user().empty() ? "" : " as " + spec.user());
  const std::string first = out.substr(0, out.find('\n'));
  return "not reachable with ssh (" + who + "): " +
         (rc < 0 ? std::string("timed out") : first.empty() ? "exit code " + std::to_string(rc) : first);
}

std::string remote_node_command(const HostPlan& h, const std::vector<std::string>& argv, int restarts, double watchdog_s) {
  std::ostringstream c;
  c << "exec " << shell_quote(h.bin() + "/fploc-remote") << " --timeout " << watchdog_s << " --restarts " << restarts
    << " --";
  for (size_t k = 0; k < argv.size(); ++k) {
    std::string a = argv[k];
    // The executable and the graph: their place on the host.
    if (k == 0 && a.find('/') != std::string::npos) a = h.map_path(a);
    if (k > 0 && argv[k - 1] == "--graph") a = h.map_path(a);
    c << ' ' << shell_quote(a);
  }
  return c.str();
}

int run_merged(const std::vector<std::string>& args, double timeout_s, std::string& out) {
  fploc::rt::RunOptions o;
  o.timeout_s = timeout_s;
  o.merge_stderr = true;
  o.search_path = true;
  fploc::rt::RunResult r = fploc::rt::run_program(args, o);
  out += r.output;
  return r.exit_code;
}

std::string local_commit(const std::string& root) {
  std::string out;
  if (run_merged({"git", "-C", root, "rev-parse", "HEAD"}, 5, out) != 0) return "";
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

namespace {

// One host's check (one ssh round trip answers everything); `exes` are the executables its nodes run.
std::vector<HostProblem> check_host(const fploc::Graph& g, const HostPlan& h, const std::set<std::string>& exes,
                                    const std::string& group) {
  std::vector<HostProblem> problems;
  const std::string commit = local_commit(h.local_root);
  std::ostringstream c;
  c << "cd " << shell_quote(h.root()) << " 2>/dev/null && echo ROOT_OK; "
    << "echo COMMIT $(git -C " << shell_quote(h.root()) << " rev-parse HEAD 2>/dev/null); "
    << "for e in " << shell_quote(h.bin() + "/fploc-remote");
  for (const auto& e : exes) c << ' ' << shell_quote(e.find('/') == std::string::npos ? e : h.map_path(e));
  c << "; do case \"$e\" in */*) test -x \"$e\" || echo MISSING \"$e\";; *) command -v \"$e\" >/dev/null || echo "
       "MISSING \"$e\";; esac; done; echo ROUTE $(ip route get "
    << group << " 2>&1 | head -1)";
  std::string out;
  const int rc = run_merged(h.probe_argv(c.str()), 10, out);
  if (rc != 0) {
    problems.push_back({h.spec.name(), h.unreachable(rc, out), true});
    return problems;
  }
  if (out.find("ROOT_OK") == std::string::npos) {
    problems.push_back({h.spec.name(), "fploc is missing: no folder " + h.root() + " (Host.fploc_root)"});
    return problems;
  }
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("MISSING ", 0) == 0)
      problems.push_back({h.spec.name(), "fploc is incomplete: " + line.substr(8) + " is not there (build it on that host)"});
    if (line.rfind("COMMIT", 0) == 0) {
      std::string theirs = line.size() > 7 ? line.substr(7) : "";
      if (!commit.empty() && theirs != commit)
        problems.push_back({h.spec.name(), "fploc at " + h.root() + " is at commit " +
                                               (theirs.empty() ? "(not a git checkout)" : theirs.substr(0, 12)) +
                                               ", this checkout at " + commit.substr(0, 12)});
    }
    const std::string iface = !h.spec.lcm_interface().empty() ? h.spec.lcm_interface() : g.lcm_interface();
    if (line.rfind("ROUTE", 0) == 0 && !iface.empty() && line.find(" dev " + iface + " ") == std::string::npos &&
        line.find(" dev " + iface) == std::string::npos)
      problems.push_back({h.spec.name(), "multicast to " + group + " does not leave through " + iface + " (" +
                                             line.substr(6) + "); e.g. `ip route add 224.0.0.0/4 dev " + iface + "`"});
  }
  return problems;
}

}  // namespace

std::vector<HostProblem> check_hosts(const fploc::Graph& g, const std::vector<HostPlan>& hosts,
                                     const std::vector<std::pair<std::string, std::string>>& host_exe,
                                     const std::string& lcm_url) {
  std::string group = "239.255.76.67";
  std::smatch m;
  if (std::regex_search(lcm_url, m, std::regex("udpm://([0-9.]+)"))) group = m[1];
  // The hosts are checked at the same time (a host that is away costs its ssh connect timeout once, not once per
  // host); their problems are reported in the graph's order of hosts.
  std::vector<std::future<std::vector<HostProblem>>> checks;
  for (const auto& h : hosts) {
    std::set<std::string> exes;
    for (const auto& [host, exe] : host_exe)
      if (host == h.spec.name()) exes.insert(exe);
    if (exes.empty()) continue;  // no enabled node runs there
    checks.push_back(std::async(std::launch::async, check_host, std::cref(g), std::cref(h), exes, group));
  }
  std::vector<HostProblem> problems;
  for (auto& c : checks)
    for (auto& p : c.get()) problems.push_back(std::move(p));
  return problems;
}

}  // namespace fploc::launch
