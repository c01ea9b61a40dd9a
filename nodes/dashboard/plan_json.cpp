#include "plan_json.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#ifdef FPLOC_HAVE_PLAN_IO
#include "fploc/floorplan/io.h"
#endif

namespace fploc::dashboard {
using nlohmann::json;

FloorPlan load_plan_file(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                         const std::string& floor) {
#ifdef FPLOC_HAVE_PLAN_IO
  return load_floor_plan(path, layers, units, floor);
#else
  (void)floor;
  // Fallback until the floorplan module's reader is there: the JSON format only, no layer filter.
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  if (path.size() < 5 || path.substr(path.size() - 5) != ".json")
    throw std::runtime_error(path + ": this build reads only .json plans (fploc/floorplan/io.h missing)");
  json j;
  try {
    j = json::parse(in);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  std::string u = units.empty() ? j.value("units", std::string("m")) : units;
  const double s = u == "m" ? 1.0 : u == "cm" ? 0.01 : u == "mm" ? 0.001 : NAN;
  if (!std::isfinite(s)) throw std::runtime_error(path + ": unknown units '" + u + "'");
  FloorPlan plan;
  plan.source = path;
  const auto& els = j.at("elements");
  for (size_t i = 0; i < els.size(); ++i) {
    const auto& e = els[i];
    try {
      const std::string t = e.at("type");
      auto v2 = [&](const char* k) { return Eigen::Vector2d(e.at(k).at(0).get<double>() * s, e.at(k).at(1).get<double>() * s); };
      if (t == "segment") plan.elements.push_back(Element::segment(v2("a"), v2("b")));
      else if (t == "circle") plan.elements.push_back(Element::circle(v2("c"), e.at("r").get<double>() * s));
      else if (t == "arc") {
        const double a0 = e.at("start_deg").get<double>() * M_PI / 180, a1 = e.at("end_deg").get<double>() * M_PI / 180;
        plan.elements.push_back(Element::arc(v2("c"), e.at("r").get<double>() * s, a0, a1 > a0 ? a1 : a1 + 2 * M_PI));
      } else throw std::runtime_error("unknown type '" + t + "'");
    } catch (const std::exception& ex) {
      throw std::runtime_error(path + ": element " + std::to_string(i) + ": " + ex.what());
    }
  }
  return plan;
#endif
}

std::string plan_to_json(const FloorPlan& plan) {
  auto r = [](double v) { return std::round(v * 1e5) / 1e5; };
  json els = json::array();
  for (const auto& e : plan.elements) {
    switch (e.kind) {
      case ElementKind::kSegment:
        els.push_back({{"type", "segment"}, {"a", {r(e.a.x()), r(e.a.y())}}, {"b", {r(e.b.x()), r(e.b.y())}}});
        break;
      case ElementKind::kCircle:
        els.push_back({{"type", "circle"}, {"c", {r(e.c.x()), r(e.c.y())}}, {"r", r(e.r)}});
        break;
      case ElementKind::kArc:
        els.push_back({{"type", "arc"}, {"c", {r(e.c.x()), r(e.c.y())}}, {"r", r(e.r)}, {"a0", e.a0}, {"a1", e.a1}});
        break;
    }
  }
  const Box2 b = plan.bounds();
  json j = {{"units", "m"}, {"source", plan.source}, {"elements", els}, {"layers", plan.layers}};
  j["bounds"] = b.empty() ? json(nullptr) : json({r(b.min.x()), r(b.min.y()), r(b.max.x()), r(b.max.y())});
  return j.dump();
}

}  // namespace fploc::dashboard
