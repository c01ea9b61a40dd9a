#include "fploc/floorplan/io.h"

#include <fnmatch.h>
#include <sys/stat.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "fploc/floorplan/binary_io.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/dxf.h"
#include "fploc/floorplan/occupancy.h"

namespace fploc {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string extension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot));
}

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace((unsigned char)s[b])) ++b;
  while (e > b && std::isspace((unsigned char)s[e - 1])) --e;
  return s.substr(b, e - b);
}

bool parse_double(const std::string& s0, double* v) {
  const std::string s = trim(s0);
  if (s.empty()) return false;
  const char* b = s.data();
  const char* e = b + s.size();
  if (*b == '+') ++b;
  auto r = std::from_chars(b, e, *v);
  return r.ec == std::errc() && r.ptr == e;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

[[noreturn]] void fail(const std::string& msg) { throw std::runtime_error(msg); }

using binary::get;
using binary::get_string;
using binary::put;
using binary::put_string;

bool finite_element(const Element& e) {
  return std::isfinite(e.a.x()) && std::isfinite(e.a.y()) && std::isfinite(e.b.x()) && std::isfinite(e.b.y()) &&
         std::isfinite(e.c.x()) && std::isfinite(e.c.y()) && std::isfinite(e.r) && std::isfinite(e.a0) &&
         std::isfinite(e.a1);
}

}  // namespace

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(path + ": cannot open (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) fail(path + ": is a directory");
  if (S_ISREG(st.st_mode) && st.st_size == 0) fail(path + ": empty file");
}

std::string read_input_file(const std::string& path) {
  check_input_file(path);
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) fail(path + ": read error");
  return ss.str();
}

double metres_per_unit(const std::string& units0) {
  const std::string u = lower(trim(units0));
  if (u == "m" || u == "meter" || u == "metre" || u == "meters" || u == "metres") return 1.0;
  if (u == "cm") return 0.01;
  if (u == "mm") return 0.001;
  if (u == "in" || u == "inch") return 0.0254;
  if (u == "ft" || u == "foot" || u == "feet") return 0.3048;
  fail("unknown units '" + units0 + "' (use m, cm, mm, in or ft)");
}

bool glob_match(const std::string& pattern, const std::string& text) {
  return fnmatch(pattern.c_str(), text.c_str(), FNM_CASEFOLD) == 0;
}

bool layer_selected(const std::vector<std::string>& globs, const std::string& layer) {
  if (globs.empty()) return true;
  for (const auto& g : globs)
    if (glob_match(g, layer)) return true;
  return false;
}

std::vector<std::string> split_layer_globs(const std::vector<std::string>& lists) {
  std::vector<std::string> out;
  for (const auto& l : lists) {
    std::stringstream ss(l);
    for (std::string g; std::getline(ss, g, ',');)
      if (!g.empty()) out.push_back(g);
  }
  return out;
}

void filter_layers(FloorPlan& plan, const std::vector<std::string>& globs) {
  if (globs.empty()) return;
  const size_t before = plan.elements.size();
  FloorPlan out;
  out.source = plan.source;
  std::vector<int> remap(plan.layers.size(), -1);
  for (const auto& e : plan.elements) {
    const std::string name = (e.layer >= 0 && e.layer < int(plan.layers.size())) ? plan.layers[e.layer] : "0";
    if (!layer_selected(globs, name)) continue;
    Element n = e;
    n.layer = out.layer_index(name);
    out.elements.push_back(n);
  }
  if (out.elements.empty() && before > 0) {
    std::string g, l;
    for (const auto& s : globs) g += (g.empty() ? "" : ",") + s;
    std::vector<std::string> names = plan.layers;
    std::sort(names.begin(), names.end());
    for (size_t i = 0; i < names.size() && i < 40; ++i) l += (l.empty() ? "" : ", ") + names[i];
    if (names.size() > 40) l += ", ...";
    fail(plan.source + ": no elements on layers matching '" + g + "' (layers with elements: " + l + ")");
  }
  plan = std::move(out);
}

void scale_plan(FloorPlan& plan, double s) {
  if (s == 1.0) return;
  for (auto& e : plan.elements) {
    e.a *= s;
    e.b *= s;
    e.c *= s;
    e.r *= s;
  }
}

FloorPlan read_plan_csv(std::istream& in, const std::string& source, const PlanLoadOptions& options) {
  FloorPlan plan;
  plan.source = source;
  const double scale = options.units_override.empty() ? 1.0 : metres_per_unit(options.units_override);
  std::string line;
  int lineno = 0;
  bool first_data = true;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (lineno == 1 && line.size() >= 3 && (unsigned char)line[0] == 0xEF && (unsigned char)line[1] == 0xBB &&
        (unsigned char)line[2] == 0xBF)
      line = line.substr(3);
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const char sep = (t.find(',') == std::string::npos && t.find(';') != std::string::npos) ? ';' : ',';
    auto cols = split(t, sep);
    if (cols.size() == 1) cols = split(t, '\t');
    double v[4];
    bool ok = cols.size() == 4 || cols.size() == 5;
    for (int i = 0; ok && i < 4; ++i) ok = parse_double(cols[i], &v[i]);
    if (!ok) {
      if (first_data) {  // header row
        first_data = false;
        continue;
      }
      fail(source + ":" + std::to_string(lineno) + ": expected 4 numbers x1,y1,x2,y2 (and an optional layer), got '" +
           t.substr(0, 80) + "'");
    }
    first_data = false;
    for (double x : v)
      if (!std::isfinite(x)) fail(source + ":" + std::to_string(lineno) + ": non-finite coordinate in '" + t + "'");
    const std::string layer = cols.size() == 5 ? trim(cols[4]) : "0";
    plan.elements.push_back(Element::segment(Eigen::Vector2d(v[0], v[1]) * scale, Eigen::Vector2d(v[2], v[3]) * scale,
                                             plan.layer_index(layer)));
  }
  if (in.bad()) fail(source + ": read error");
  if (plan.elements.empty()) fail(source + ": no segments (expected rows x1,y1,x2,y2)");
  filter_layers(plan, options.layer_globs);
  return plan;
}

FloorPlan read_plan_json(std::istream& in, const std::string& source, const PlanLoadOptions& options) {
  using nlohmann::json;
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    fail(source + ": " + e.what());
  }
  FloorPlan plan;
  plan.source = source;
  if (!j.is_object()) fail(source + ": expected a JSON object with \"elements\"");
  // Every key must be known: a misspelt one ("unit") would otherwise be a silent default.
  auto known_keys = [](std::initializer_list<const char*> keys) {
    std::string l;
    for (const char* k : keys) l += (l.empty() ? "" : ", ") + std::string(k);
    return l;
  };
  auto check_keys = [&](const json& o, std::initializer_list<const char*> keys, const std::string& what) {
    for (const auto& [k, v] : o.items()) {
      bool ok = false;
      for (const char* known : keys) ok = ok || k == known;
      if (!ok) fail(what + "unknown key \"" + k + "\" (known keys: " + known_keys(keys) + ")");
    }
  };
  check_keys(j, {"units", "elements"}, source + ": ");
  std::string units = "m";
  if (j.contains("units")) {
    if (!j["units"].is_string()) fail(source + ": \"units\" must be a string");
    units = j["units"].get<std::string>();
  }
  if (!options.units_override.empty()) units = options.units_override;
  double scale;
  try {
    scale = metres_per_unit(units);
  } catch (const std::exception& e) {
    fail(source + ": " + e.what());
  }
  if (!j.contains("elements") || !j["elements"].is_array()) fail(source + ": missing array \"elements\"");
  const auto& els = j["elements"];
  for (size_t i = 0; i < els.size(); ++i) {
    const std::string where = source + ": elements[" + std::to_string(i) + "]";
    const auto& o = els[i];
    try {
      if (!o.is_object()) fail("not an object");
      const std::string type = o.value("type", std::string("segment"));
      auto vec = [&](const char* key) {
        if (!o.contains(key)) fail(std::string("missing \"") + key + "\"");
        const auto& a = o[key];
        if (!a.is_array() || a.size() < 2 || !a[0].is_number() || !a[1].is_number())
          fail(std::string("\"") + key + "\" must be [x, y]");
        return Eigen::Vector2d(a[0].get<double>(), a[1].get<double>()) * scale;
      };
      auto num = [&](const char* key) {
        if (!o.contains(key) || !o[key].is_number()) fail(std::string("missing number \"") + key + "\"");
        return o[key].get<double>();
      };
      const int layer = plan.layer_index(o.contains("layer") && o["layer"].is_string() ? o["layer"].get<std::string>() : "0");
      if (type == "segment" || type == "line") check_keys(o, {"type", "a", "b", "layer"}, type + ": ");
      else if (type == "circle") check_keys(o, {"type", "c", "r", "layer"}, "circle: ");
      else if (type == "arc") check_keys(o, {"type", "c", "r", "start_deg", "end_deg", "layer"}, "arc: ");
      Element e;
      if (type == "segment" || type == "line") {
        e = Element::segment(vec("a"), vec("b"), layer);
      } else if (type == "circle") {
        e = Element::circle(vec("c"), num("r") * scale, layer);
        if (!(e.r > 0)) fail("radius must be > 0");
      } else if (type == "arc") {
        e = Element::arc(vec("c"), num("r") * scale, num("start_deg") * M_PI / 180, num("end_deg") * M_PI / 180, layer);
        if (!(e.r > 0)) fail("radius must be > 0");
      } else {
        fail("unknown type '" + type + "' (segment, circle, arc)");
      }
      if (!finite_element(e)) fail("non-finite coordinate");
      plan.elements.push_back(e);
    } catch (const nlohmann::json::exception& ex) {
      fail(where + ": " + ex.what());
    } catch (const std::runtime_error& ex) {
      fail(where + ": " + ex.what());
    }
  }
  filter_layers(plan, options.layer_globs);
  return plan;
}

void write_plan_json(const FloorPlan& plan, std::ostream& out) {
  using nlohmann::json;
  json j;
  j["units"] = "m";
  json els = json::array();
  for (const auto& e : plan.elements) {
    json o;
    switch (e.kind) {
      case ElementKind::kSegment:
        o["type"] = "segment";
        o["a"] = {e.a.x(), e.a.y()};
        o["b"] = {e.b.x(), e.b.y()};
        break;
      case ElementKind::kCircle:
        o["type"] = "circle";
        o["c"] = {e.c.x(), e.c.y()};
        o["r"] = e.r;
        break;
      case ElementKind::kArc:
        o["type"] = "arc";
        o["c"] = {e.c.x(), e.c.y()};
        o["r"] = e.r;
        o["start_deg"] = e.a0 * 180 / M_PI;
        o["end_deg"] = e.a1 * 180 / M_PI;
        break;
    }
    if (e.layer >= 0 && e.layer < int(plan.layers.size())) o["layer"] = plan.layers[e.layer];
    els.push_back(o);
  }
  j["elements"] = els;
  out << j.dump(1) << "\n";
  if (!out) fail("write error");
}

void write_plan_csv(const FloorPlan& plan, std::ostream& out, double chord_tolerance) {
  out << "x1,y1,x2,y2,layer\n";
  out.precision(17);
  auto row = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, int layer) {
    out << a.x() << "," << a.y() << "," << b.x() << "," << b.y() << ","
        << ((layer >= 0 && layer < int(plan.layers.size())) ? plan.layers[layer] : std::string("0")) << "\n";
  };
  for (const auto& e : plan.elements) {
    if (e.kind == ElementKind::kSegment) {
      row(e.a, e.b, e.layer);
      continue;
    }
    const double sweep = e.a1 - e.a0;
    const double tol = std::max(chord_tolerance, 1e-9);
    const double step = e.r > tol ? 2 * std::acos(1 - tol / e.r) : M_PI / 2;
    const int n = std::max(e.kind == ElementKind::kCircle ? 8 : 1, int(std::ceil(sweep / std::max(step, 1e-3))));
    Eigen::Vector2d prev = e.c + e.r * Eigen::Vector2d(std::cos(e.a0), std::sin(e.a0));
    for (int k = 1; k <= n; ++k) {
      const double t = e.a0 + sweep * k / n;
      const Eigen::Vector2d p = e.c + e.r * Eigen::Vector2d(std::cos(t), std::sin(t));
      row(prev, p, e.layer);
      prev = p;
    }
  }
  if (!out) fail("write error");
}

void save_floor_plan(const FloorPlan& plan, const std::string& path) {
  const std::string ext = extension(path);
  // The extension first: opening the file empties it (a user's building.dxf given as --out).
  if (ext != ".json" && ext != ".csv") fail(path + ": unsupported extension '" + ext + "' (use .json or .csv)");
  std::ofstream f(path);
  if (!f) fail(path + ": cannot write (" + std::strerror(errno) + ")");
  try {
    if (ext == ".json")
      write_plan_json(plan, f);
    else
      write_plan_csv(plan, f);
  } catch (const std::runtime_error& e) {
    fail(path + ": " + e.what());
  }
}

void write_plan_binary(const FloorPlan& plan, std::ostream& out) {
  put_string(out, plan.source);
  put<uint32_t>(out, uint32_t(plan.layers.size()));
  for (const auto& l : plan.layers) put_string(out, l);
  put<uint64_t>(out, uint64_t(plan.elements.size()));
  for (const auto& e : plan.elements) {
    put<uint8_t>(out, uint8_t(e.kind));
    put<int32_t>(out, int32_t(e.layer));
    for (double v : {e.a.x(), e.a.y(), e.b.x(), e.b.y(), e.c.x(), e.c.y(), e.r, e.a0, e.a1}) put<double>(out, v);
  }
}

FloorPlan read_plan_binary(std::istream& in, const std::string& source) {
  FloorPlan plan;
  plan.source = get_string(in, source);
  const uint32_t nl = get<uint32_t>(in, source);
  if (nl > (1u << 20)) fail(source + ": corrupt map file (layer count)");
  for (uint32_t i = 0; i < nl; ++i) plan.layers.push_back(get_string(in, source));
  const uint64_t ne = get<uint64_t>(in, source);
  if (ne > (1ull << 28)) fail(source + ": corrupt map file (element count)");
  plan.elements.resize(ne);
  for (auto& e : plan.elements) {
    const uint8_t k = get<uint8_t>(in, source);
    if (k > 2) fail(source + ": corrupt map file (element kind " + std::to_string(k) + ")");
    e.kind = ElementKind(k);
    e.layer = get<int32_t>(in, source);
    if (e.layer < -1 || e.layer >= int(nl)) fail(source + ": corrupt map file (layer index)");
    double v[9];
    for (double& x : v) x = get<double>(in, source);
    e.a = {v[0], v[1]};
    e.b = {v[2], v[3]};
    e.c = {v[4], v[5]};
    e.r = v[6];
    e.a0 = v[7];
    e.a1 = v[8];
    if (!finite_element(e)) fail(source + ": corrupt map file (non-finite element)");
  }
  return plan;
}

void read_fpmap_header(std::istream& in, const std::string& source) {
  char magic[8] = {};
  in.read(magic, 8);
  if (!in || std::memcmp(magic, kFpmapMagic, 8) != 0) fail(source + ": not an fploc map (.fpmap) file");
  const uint32_t version = get<uint32_t>(in, source);
  if (version != kFpmapVersion)
    fail(source + ": map version " + std::to_string(version) + ", this build reads version " +
         std::to_string(kFpmapVersion) + " (rebuild it with `fploc map build`)");
}

FloorPlan read_plan_from_fpmap(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path + ": cannot open (" + std::strerror(errno) + ")");
  read_fpmap_header(f, path);
  return read_plan_binary(f, path);
}

FloorPlan load_floor_plan(const std::string& path, const std::vector<std::string>& layer_globs,
                          const std::string& units_override, const std::string& floor) {
  PlanLoadOptions o;
  o.layer_globs = layer_globs;
  o.units_override = units_override;
  o.floor = floor;
  return load_floor_plan(path, o);
}

FloorPlan load_floor_plan(const std::string& path, const PlanLoadOptions& options_in) {
  // Layer globs are comma-separated lists wherever they come from (--layers 'A,B', plan.layers: "A,B").
  PlanLoadOptions options = options_in;
  options.layer_globs = split_layer_globs(options_in.layer_globs);
  const std::string ext = extension(path);
  check_input_file(path);
  if (is_building_file(path)) {
    BuildingLoadOptions bo;
    bo.ifc_cut_height = options.ifc_cut_height;
    bo.quiet = options.quiet;
    return load_floor_plan(load_building(path, bo), options.floor, options);
  }
  if (!options.floor.empty() && options.floor != "0")
    fail(path + ": floor '" + options.floor + "' requested, but a single plan has one floor (\"0\"); give a building "
         "(.pbtxt) or an .ifc file");
  FloorPlan plan;
  if (ext == ".csv") {
    std::ifstream f(path);
    if (!f) fail(path + ": cannot open (" + std::strerror(errno) + ")");
    plan = read_plan_csv(f, path, options);
  } else if (ext == ".json") {
    std::ifstream f(path);
    if (!f) fail(path + ": cannot open (" + std::strerror(errno) + ")");
    plan = read_plan_json(f, path, options);
  } else if (ext == ".dxf") {
    plan = read_plan_dxf(read_input_file(path), path, options);
  } else if (ext == ".fpmap") {
    plan = read_plan_from_fpmap(path);
    if (!options.units_override.empty() && metres_per_unit(options.units_override) != 1.0)
      fail(path + ": a built map is already in metres; --units does not apply");
    filter_layers(plan, options.layer_globs);
  } else if (ext == ".yaml" || ext == ".yml") {  // ROS map_server occupancy map (fploc/floorplan/occupancy.h)
    plan = load_occupancy_plan(path);
    if (!options.units_override.empty() && metres_per_unit(options.units_override) != 1.0)
      fail(path + ": an occupancy map is in metres (its resolution); --units does not apply");
  } else {
    fail(path + ": unknown floor-plan format '" + ext + "' (use .dxf, .csv, .json, .fpmap, a map_server .yaml, a building .pbtxt or .ifc)");
  }
  if (plan.elements.empty()) fail(path + ": the plan has no elements");
  plan.source = path;
  return plan;
}

}  // namespace fploc
