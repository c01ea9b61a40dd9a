#include "fploc/floorplan/ifc.h"

#include "fploc/floorplan/io.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace fploc {
namespace {

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Runs argv with stdout/stderr into files; returns the exit status (or -1 when it could not start).
int run(const std::vector<std::string>& args, const std::string& out, const std::string& err, std::string* why) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid;
  const int rc = posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    *why = std::strerror(rc);
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  *why = "killed by signal " + std::to_string(WTERMSIG(status));
  return -1;
}

struct TempDir {
  std::string path;
  TempDir() {
    std::string t = (std::filesystem::temp_directory_path() / "fploc-ifc-XXXXXX").string();
    if (!mkdtemp(t.data())) fail(std::string("cannot create a temporary folder: ") + std::strerror(errno));
    path = t;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

Eigen::Vector2d point(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number()) fail(where + ": expected [x, y]");
  const Eigen::Vector2d p(j[0].get<double>(), j[1].get<double>());
  if (!p.allFinite()) fail(where + ": not finite");
  return p;
}

}  // namespace

std::string ifc2plan_script() {
  if (const char* e = std::getenv("FPLOC_IFC2PLAN"); e && *e) return e;
  return std::string(FPLOC_SOURCE_DIR) + "/tools/ifc/ifc2plan.mjs";
}

Building building_from_ifc_json(const std::string& text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    fail(source + ": the IFC reader's output is not JSON (" + e.what() + ")");
  }
  Building b;
  b.source = source;
  b.name = std::filesystem::path(source).stem().string();
  if (!j.contains("storeys") || !j["storeys"].is_array()) fail(source + ": the IFC reader's output has no storeys");
  for (const auto& s : j["storeys"]) {
    BuildingFloor f;
    f.name = s.value("name", std::string());
    const std::string where = source + ": storey '" + f.name + "'";
    f.plan_file = source;
    f.plan_floor = f.name;
    f.elevation = s.value("elevation", 0.0);
    f.ceiling_height = s.value("ceiling_height", 0.0);
    if (!std::isfinite(f.elevation) || !std::isfinite(f.ceiling_height) || f.ceiling_height < 0)
      fail(where + ": bad elevation or ceiling height");
    auto plan = std::make_shared<FloorPlan>();
    plan->source = source;
    for (const auto& e : s.value("elements", nlohmann::json::array())) {
      const std::string ew = where + ": element #" + std::to_string(e.value("id", 0));
      plan->elements.push_back(Element::segment(point(e.at("a"), ew), point(e.at("b"), ew),
                                                plan->layer_index(e.value("layer", std::string("0")))));
    }
    for (const auto& sp : s.value("spaces", nlohmann::json::array())) {
      CeilingArea a;
      a.name = sp.value("name", std::string());
      a.height = sp.value("ceiling_height", 0.0);
      for (const auto& p : sp.at("polygon")) a.polygon.push_back(point(p, where + ": space '" + a.name + "'"));
      if (a.polygon.size() >= 3 && a.height > 0 && std::isfinite(a.height)) f.areas.push_back(std::move(a));
    }
    f.plan = std::move(plan);
    b.floors.push_back(std::move(f));
  }
  if (b.floors.empty()) fail(source + ": the model has no storey");
  for (const auto& w : j.value("warnings", nlohmann::json::array()))
    if (w.is_string()) b.warnings.push_back(w.get<std::string>());
  return b;
}

Building read_ifc_building(const std::string& path, const IfcReadOptions& options) {
  check_input_file(path);
  if (!(options.cut_height > 0) || !std::isfinite(options.cut_height)) fail(path + ": IFC cut height must be > 0");
  const std::string script = ifc2plan_script();
  if (!std::filesystem::exists(script)) fail(path + ": the IFC reader " + script + " is missing");
  const std::filesystem::path modules = std::filesystem::path(script).parent_path() / "node_modules" / "web-ifc";
  if (!std::filesystem::exists(modules))
    fail(path + ": reading IFC needs web-ifc (npm) in " + modules.parent_path().string() +
         ": run scripts/setup-web.sh (or `npm ci` in " + std::filesystem::path(script).parent_path().string() + ")");
  const char* node_env = std::getenv("FPLOC_NODE");
  const std::string node = node_env && *node_env ? node_env : "node";
  TempDir tmp;
  const std::string out = tmp.path + "/out.json", err = tmp.path + "/err.txt";
  std::ostringstream cut;
  cut.precision(17);
  cut << options.cut_height;
  std::string why;
  const int rc = run({node, script, "--cut-height", cut.str(), path}, out, err, &why);
  if (rc < 0) fail(path + ": cannot run the IFC reader (" + node + ": " + why + "); is Node.js installed?");
  if (rc != 0) {
    std::string msg = slurp(err);
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == '\r')) msg.pop_back();
    if (msg.empty()) msg = path + ": the IFC reader failed (exit status " + std::to_string(rc) + ")";
    // Warnings it printed before failing (elements it left out) stay warnings, not part of the error.
    if (rc == 2) {
      std::istringstream lines(msg);
      std::string line, rest;
      while (std::getline(lines, line)) {
        if (line.find(": warning: ") != std::string::npos) {
          if (!options.quiet) std::cerr << line << "\n";
        } else {
          rest += (rest.empty() ? "" : "\n") + line;
        }
      }
      if (!rest.empty()) msg = rest;
    }
    // Node's own errors are long: keep the first line, it names the problem.
    if (rc != 2) msg = path + ": the IFC reader failed: " + msg.substr(0, msg.find('\n'));
    fail(msg);
  }
  Building b = building_from_ifc_json(slurp(out), path);
  if (!options.quiet) {
    for (const auto& w : b.warnings) std::cerr << w << "\n";
    if (b.warnings.size() > 1)
      std::cerr << path << ": " << b.warnings.size() << " elements with representation items the IFC reader does not "
                << "handle (left out of the plan, in whole or in part)\n";
    // What was read, as the DXF reader says it: each storey's elements, extents and elevation (metres).
    std::ostringstream sum;
    sum.precision(4);
    sum << path << ": " << b.floors.size() << (b.floors.size() == 1 ? " storey" : " storeys") << ", walls cut "
        << options.cut_height << " m above each floor:";
    for (size_t k = 0; k < b.floors.size(); ++k) {
      if (k == 6) {
        sum << " ... (" << b.floors.size() - k << " more)";
        break;
      }
      const auto& f = b.floors[k];
      sum << (k ? ";" : "") << " '" << f.name << "' " << f.plan->elements.size() << " elements";
      if (!f.plan->elements.empty()) {
        const Box2 e = f.plan->bounds();
        sum << ", " << e.size().x() << " x " << e.size().y() << " m";
      }
      sum << " at " << f.elevation << " m";
    }
    std::cerr << sum.str() << "\n";
  }
  return b;
}

}  // namespace fploc
