#include "fploc/config/plan_source.h"

#include <stdexcept>
#include <vector>

#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"

namespace fploc::config {

matcher::LocalizationMap load_map(const PlanSource& plan, const std::string& lookup,
                         const std::function<std::string(const std::string&)>& resolve, const std::string& field) {
  if (plan.file().empty()) throw std::runtime_error(field + ".file: no floor plan given");
  const std::vector<std::string> layers(plan.layers().begin(), plan.layers().end());
  const std::string path = resolve(plan.file());
  const std::string how = lookup.empty() ? "annf-exact" : lookup;
  if (is_building_file(path) || !plan.floor().empty()) {  // a building (.pbtxt) or IFC: the plan of one floor
    matcher::LocalizationMap m = matcher::make_localization_map(load_floor_plan(path, layers, plan.units(), plan.floor()), how);
    m.note = "loaded " + path + " floor '" + plan.floor() + "'" + (m.note.empty() ? "" : "; " + m.note);
    return m;
  }
  return matcher::load_localization_map(path, layers, plan.units(), how);
}

localizer::FloorMaps load_floor_maps(const PlanSource& plan, const std::string& lookup,
                                     const std::function<std::string(const std::string&)>& resolve,
                                     const std::string& field) {
  const std::string path = plan.file().empty() ? "" : resolve(plan.file());
  if (!path.empty() && is_building_file(path)) {
    const std::vector<std::string> layers(plan.layers().begin(), plan.layers().end());
    return localizer::load_floor_maps(path, layers, plan.units(), plan.floor(), lookup);
  }
  return localizer::one_floor(load_map(plan, lookup, resolve, field), path);
}

}  // namespace fploc::config
