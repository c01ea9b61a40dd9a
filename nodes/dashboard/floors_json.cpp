#include "floors_json.h"

#include <nlohmann/json.hpp>

#include "fploc/core/text_out.h"
#include "fploc/floorplan/building.h"
#include "plan_json.h"

namespace fploc::dashboard {

FloorPlans load_floor_plans(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                            const std::string& floor) {
  FloorPlans out;
  nlohmann::json list = nlohmann::json::array();
  if (!is_building_file(path)) {
    out.plan_json["0"] = plan_to_json(load_plan_file(path, layers, units, floor));
    out.initial = "0";
    list.push_back({{"index", 0}, {"name", "0"}, {"elevation", 0.0}});
  } else {
    const Building b = load_building(path);
    out.initial = b.floor(floor).name;  // throws naming the floors
    PlanLoadOptions o;
    o.layer_globs = layers;
    o.units_override = units;
    for (size_t i = 0; i < b.floors.size(); ++i) {
      const auto& f = b.floors[i];
      out.plan_json[f.name] = plan_to_json(load_floor_plan(b, f.name, o));
      list.push_back({{"index", i}, {"name", f.name}, {"elevation", f.elevation}});
    }
  }
  out.floors_json = fploc::json_text(nlohmann::json({{"floors", list}, {"initial", out.initial}}));
  return out;
}

}  // namespace fploc::dashboard
