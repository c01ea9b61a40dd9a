#include "fploc/localizer/floor_maps.h"

namespace fploc::localizer {

FloorMaps load_floor_maps(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                          const std::string& floor, const std::string& lookup) {
  FloorMaps m;
  auto b = std::make_shared<Building>(load_building(path));
  m.initial = b->floor_index(b->floor(floor).name);  // throws naming the floors
  PlanLoadOptions o;
  o.layer_globs = layers;
  o.units_override = units;
  for (const auto& f : b->floors) {
    matcher::LocalizationMap lm = matcher::make_localization_map(load_floor_plan(*b, f.name, o), lookup.empty() ? "annf-exact" : lookup);
    if (!f.plan) matcher::add_occupancy_extras(lm, f.plan_file);  // a floor drawn as a map_server map
    lm.note = "floor '" + f.name + "'" + (lm.note.empty() ? "" : ": " + lm.note);
    m.maps.push_back(std::move(lm));
  }
  m.building = std::move(b);
  return m;
}

FloorMaps one_floor(matcher::LocalizationMap map, const std::string& source) {
  FloorMaps m;
  auto b = std::make_shared<Building>();
  b->source = source;
  BuildingFloor f;
  f.name = "0";
  f.plan_file = source;
  f.plan = map.plan;
  b->floors.push_back(std::move(f));
  m.building = std::move(b);
  m.maps.push_back(std::move(map));
  return m;
}

}  // namespace fploc::localizer
