#include "fploc/config/floor_ref.h"

#include <algorithm>
#include <cctype>

#include "fploc/floorplan/building.h"

namespace fploc::config {

static std::string lower_ext(const std::string& p) {
  const auto dot = p.find_last_of('.');
  if (dot == std::string::npos || p.find_first_of('/', dot) != std::string::npos) return "";
  std::string e = p.substr(dot);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

FloorRef floor_ref(const PlanSource& plan, const std::string& path) {
  const std::string ext = lower_ext(path);
  if (ext == ".pbtxt") {
    const Building b = load_building(path);
    const BuildingFloor& f = b.floor(plan.floor());  // throws naming the floors
    return {b.floor_index(f.name), f.name, f.elevation};
  }
  if (ext == ".ifc") return {plan.floor().empty() ? 0 : -1, plan.floor(), 0.0};
  return {0, plan.floor().empty() ? "0" : plan.floor(), 0.0};
}

}  // namespace fploc::config
