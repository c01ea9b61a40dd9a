#include "plan_json.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "fploc/core/text_out.h"
#include "fploc/floorplan/io.h"

namespace fploc::dashboard {
using nlohmann::json;

FloorPlan load_plan_file(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                         const std::string& floor) {
  return load_floor_plan(path, layers, units, floor);
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
  return fploc::json_text(j);
}

}  // namespace fploc::dashboard
