#include "fploc/floorplan/building.h"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "building.pb.h"
#include "fploc/floorplan/ifc.h"
#include "fploc/floorplan/io.h"

namespace fploc {
namespace {

namespace pb = google::protobuf;

[[noreturn]] void fail(const std::string& m) { throw std::runtime_error(m); }

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

// Even-odd rule; points on the boundary count as inside for the usual floating-point cases.
bool point_in_polygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Eigen::Vector2d &a = poly[i], &b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      in = !in;
  }
  return in;
}

// First error only: the one that matters (later ones are usually consequences).
class FirstError : public pb::io::ErrorCollector {
 public:
  void AddError(int line, pb::io::ColumnNumber col, const std::string& msg) override {
    if (line_ < 0) {
      line_ = line + 1;
      col_ = col + 1;
      msg_ = msg;
    }
  }
  void AddWarning(int, pb::io::ColumnNumber, const std::string&) override {}
  int line_ = -1, col_ = 0;
  std::string msg_;
};

// Semantic checks with the line of the offending field (from the parser's location tree).
struct Checker {
  const std::string& source;
  const pb::TextFormat::ParseInfoTree& tree;

  int line_of(const pb::TextFormat::ParseInfoTree* t, const pb::Message& m, const char* field, int index) const {
    if (!t) return 0;
    const auto* f = m.GetDescriptor()->FindFieldByName(field);
    if (!f) return 0;
    const auto loc = t->GetLocation(f, f->is_repeated() ? index : -1);
    return loc.line >= 0 ? loc.line + 1 : 0;
  }
  [[noreturn]] void error(int line, const std::string& where, const std::string& msg) const {
    fail(source + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + where + ": " + msg);
  }
};

std::vector<Eigen::Vector2d> polygon_of(const pb::RepeatedPtrField<PlanPoint>& pts, const Checker& c, int line,
                                        const std::string& where) {
  std::vector<Eigen::Vector2d> poly;
  for (const auto& q : pts) {
    if (!std::isfinite(q.x()) || !std::isfinite(q.y())) c.error(line, where, "polygon vertex is not finite");
    poly.emplace_back(q.x(), q.y());
  }
  if (poly.size() < 3) c.error(line, where, "polygon needs at least 3 vertices, got " + std::to_string(poly.size()));
  double area2 = 0;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    area2 += poly[j].x() * poly[i].y() - poly[i].x() * poly[j].y();
  if (!(std::abs(area2) > 1e-9)) c.error(line, where, "polygon has zero area");
  return poly;
}

}  // namespace

bool CeilingArea::contains(const Eigen::Vector2d& p) const { return point_in_polygon(polygon, p); }
bool FloorConnection::contains(const Eigen::Vector2d& p) const { return point_in_polygon(polygon, p); }

const CeilingArea* BuildingFloor::area_at(const Eigen::Vector2d& p) const {
  for (const auto& a : areas)
    if (a.contains(p)) return &a;
  return nullptr;
}

double BuildingFloor::ceiling_height_at(const Eigen::Vector2d& p) const {
  const CeilingArea* a = area_at(p);
  return a ? a->height_at(p) : ceiling_height;
}

const char* to_string(ConnectionKind k) {
  switch (k) {
    case ConnectionKind::kStairs: return "stairs";
    case ConnectionKind::kRamp: return "ramp";
    case ConnectionKind::kLift: return "lift";
  }
  return "?";
}

int Building::floor_index(const std::string& n) const {
  if (n.empty()) return floors.empty() ? -1 : 0;
  for (size_t i = 0; i < floors.size(); ++i)
    if (floors[i].name == n) return int(i);
  return -1;
}

const BuildingFloor& Building::floor(const std::string& n) const {
  const int i = floor_index(n);
  if (i < 0) {
    std::string names;
    for (const auto& f : floors) names += (names.empty() ? "" : ", ") + f.name;
    fail(source + ": no floor '" + n + "' (floors: " + (names.empty() ? "none" : names) + ")");
  }
  return floors[size_t(i)];
}

bool is_building_file(const std::string& path) {
  const std::string e = lower_ext(path);
  return e == ".pbtxt" || e == ".ifc";
}

Building parse_building(const std::string& text, const std::string& source) {
  fploc::BuildingSpec msg;
  pb::TextFormat::Parser parser;
  FirstError errors;
  pb::TextFormat::ParseInfoTree tree;
  parser.RecordErrorsTo(&errors);
  parser.WriteLocationsTo(&tree);
  if (!parser.ParseFromString(text, &msg) || errors.line_ > 0)
    fail(source + ":" + std::to_string(std::max(errors.line_, 1)) + ":" + std::to_string(errors.col_) + ": " +
         (errors.msg_.empty() ? "cannot parse the building description" : errors.msg_));
  const Checker c{source, tree};
  const std::filesystem::path dir = std::filesystem::path(source).parent_path();
  Building b;
  b.name = msg.name();
  b.source = source;
  if (msg.floor_size() == 0) c.error(0, "floor", "a building needs at least one floor");
  std::set<std::string> names;
  for (int i = 0; i < msg.floor_size(); ++i) {
    const fploc::FloorSpec& f = msg.floor(i);
    const int line = c.line_of(&tree, msg, "floor", i);
    const auto* sub = tree.GetTreeForNested(msg.GetDescriptor()->FindFieldByName("floor"), i);
    const std::string where = "floor[" + std::to_string(i) + "]" + (f.name().empty() ? "" : " (" + f.name() + ")");
    auto fline = [&](const char* field) {
      const int l = c.line_of(sub, f, field, -1);
      return l > 0 ? l : line;
    };
    if (f.name().empty()) c.error(line, where, "name is empty");
    if (!names.insert(f.name()).second) c.error(fline("name"), where, "name '" + f.name() + "' used by another floor");
    if (f.plan().file().empty()) c.error(fline("plan"), where + ".plan.file", "no plan file");
    if (!std::isfinite(f.elevation_m())) c.error(fline("elevation_m"), where + ".elevation_m", "not finite");
    if (!(f.ceiling_height_m() > 0) || !std::isfinite(f.ceiling_height_m()))
      c.error(fline("ceiling_height_m"), where + ".ceiling_height_m", "must be > 0 (metres above the floor)");
    BuildingFloor bf;
    bf.name = f.name();
    std::filesystem::path p(f.plan().file());
    bf.plan_file = (p.is_absolute() || dir.empty() ? p : dir / p).lexically_normal().string();
    if (is_building_file(bf.plan_file) && lower_ext(bf.plan_file) != ".ifc")
      c.error(fline("plan"), where + ".plan.file", "a building cannot be the plan of a floor");
    bf.layers.assign(f.plan().layers().begin(), f.plan().layers().end());
    bf.units = f.plan().units();
    if (!bf.units.empty()) {
      try {
        metres_per_unit(bf.units);
      } catch (const std::exception& e) {
        c.error(fline("plan"), where + ".plan.units", e.what());
      }
    }
    bf.plan_floor = f.plan().floor();
    bf.elevation = f.elevation_m();
    bf.ceiling_height = f.ceiling_height_m();
    for (int k = 0; k < f.area_size(); ++k) {
      const fploc::CeilingAreaSpec& a = f.area(k);
      const int aline = sub ? c.line_of(sub, f, "area", k) : line;
      const std::string aw = where + ".area[" + std::to_string(k) + "]" + (a.name().empty() ? "" : " (" + a.name() + ")");
      CeilingArea ca;
      ca.name = a.name();
      ca.polygon = polygon_of(a.polygon(), c, aline, aw);
      if (a.ceiling_case() == fploc::CeilingAreaSpec::kCeilingHeightM) {
        ca.height = a.ceiling_height_m();
      } else if (a.ceiling_case() == fploc::CeilingAreaSpec::kSlopedCeiling) {
        const auto& s = a.sloped_ceiling();
        ca.height = s.height_m();
        ca.origin = {s.x(), s.y()};
        ca.slope = {s.slope_x(), s.slope_y()};
        if (!ca.origin.allFinite() || !ca.slope.allFinite())
          c.error(aline, aw + ".sloped_ceiling", "values must be finite");
      } else {
        c.error(aline, aw, "needs ceiling_height_m or sloped_ceiling");
      }
      if (!(ca.height > 0) || !std::isfinite(ca.height)) c.error(aline, aw, "ceiling height must be > 0");
      for (const auto& v : ca.polygon)
        if (!(ca.height_at(v) > 0)) c.error(aline, aw + ".sloped_ceiling", "the ceiling reaches the floor inside the area");
      bf.areas.push_back(std::move(ca));
    }
    b.floors.push_back(std::move(bf));
  }
  for (int i = 0; i < msg.connection_size(); ++i) {
    const fploc::FloorConnectionSpec& k = msg.connection(i);
    const int line = c.line_of(&tree, msg, "connection", i);
    const std::string where = "connection[" + std::to_string(i) + "]" + (k.name().empty() ? "" : " (" + k.name() + ")");
    if (k.kind() == fploc::FloorConnectionSpec::UNKNOWN) c.error(line, where + ".kind", "missing (STAIRS, RAMP or LIFT)");
    for (const std::string* fl : {&k.from_floor(), &k.to_floor()})
      if (b.floor_index(*fl) < 0 || fl->empty())
        c.error(line, where, "unknown floor '" + *fl + "' (from_floor/to_floor must name floors of this building)");
    if (k.from_floor() == k.to_floor()) c.error(line, where, "from_floor and to_floor are the same floor");
    FloorConnection fc;
    fc.name = k.name();
    fc.kind = ConnectionKind(int(k.kind()));
    fc.from_floor = k.from_floor();
    fc.to_floor = k.to_floor();
    fc.polygon = polygon_of(k.polygon(), c, line, where);
    b.connections.push_back(std::move(fc));
  }
  return b;
}

Building load_building(const std::string& path, const BuildingLoadOptions& options) {
  const std::string ext = lower_ext(path);
  check_input_file(path);
  if (ext == ".ifc") {
    IfcReadOptions io;
    io.cut_height = options.ifc_cut_height;
    io.quiet = options.quiet;
    return read_ifc_building(path, io);
  }
  if (ext == ".pbtxt") {
    std::ifstream f(path, std::ios::binary);
    if (!f) fail(path + ": cannot open building file (" + std::strerror(errno) + ")");
    std::ostringstream ss;
    ss << f.rdbuf();
    return parse_building(ss.str(), path);
  }
  Building b;
  b.source = path;
  BuildingFloor f;
  f.name = "0";
  f.plan_file = path;
  b.floors.push_back(std::move(f));
  return b;
}

FloorPlan load_floor_plan(const Building& building, const std::string& floor, const PlanLoadOptions& options) {
  const BuildingFloor& f = building.floor(floor);
  PlanLoadOptions o = options;
  o.floor = f.plan_floor;
  if (o.layer_globs.empty()) o.layer_globs = f.layers;
  if (o.units_override.empty()) o.units_override = f.units;
  FloorPlan plan;
  try {
    if (f.plan) {
      plan = *f.plan;
      if (!o.units_override.empty() && metres_per_unit(o.units_override) != 1.0)
        fail(f.plan_file + ": an IFC storey is already in metres; units do not apply");
      filter_layers(plan, o.layer_globs);
    } else {
      plan = load_floor_plan(f.plan_file, o);
    }
  } catch (const std::exception& e) {
    fail(building.source + ": floor '" + f.name + "': " + e.what());
  }
  if (plan.elements.empty()) fail(building.source + ": floor '" + f.name + "': the plan has no elements");
  return plan;
}

}  // namespace fploc
