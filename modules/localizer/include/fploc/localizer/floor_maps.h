// Every floor's localization map of a building (the matcher, optimizer and relocalizer switch between
// them when the robot changes floor). Each floor's ANNF comes from the cache (fploc/annf/cache.h), keyed
// by that floor's plan, so a building's fields are built once and shared by the nodes.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "fploc/floorplan/building.h"
#include "fploc/matcher/map.h"

namespace fploc::localizer {

struct FloorMaps {
  std::shared_ptr<const Building> building;
  std::vector<matcher::LocalizationMap> maps;  // one per building floor, same order
  int initial = 0;                    // the floor named by the option ("" = the first)
  bool multi_floor() const { return maps.size() > 1; }
};

// `path`: a building (.pbtxt) or IFC file (every floor is loaded), layers/units as the plan option
// (they replace each floor's own when given), `floor` the initial floor's name. Throws naming the file
// and floor.
FloorMaps load_floor_maps(const std::string& path, const std::vector<std::string>& layers, const std::string& units,
                          const std::string& floor, const std::string& lookup);
// A map already loaded (a single plan): a one-floor building named "0".
FloorMaps one_floor(matcher::LocalizationMap map, const std::string& source);

}  // namespace fploc::localizer
