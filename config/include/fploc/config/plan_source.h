// Options PlanSource (+ look-up name) -> the localization map a node loads.
#pragma once
#include <functional>
#include <string>

#include "fploc/localizer/floor_maps.h"
#include "fploc/matcher/map.h"
#include "options/common.pb.h"

namespace fploc::config {

// The map of a node's `plan` option with the named look-up ("" = annf-exact); `resolve` turns the
// option's path (relative to the graph file) into a file name. Throws naming `field`.file when no plan
// is given.
matcher::LocalizationMap load_map(const PlanSource& plan, const std::string& lookup,
                         const std::function<std::string(const std::string&)>& resolve, const std::string& field);

// Every floor of the option's building (`.pbtxt`/`.ifc`: one map per floor, the option's `floor` first to
// be used), or the option's single plan as a one-floor building. Throws naming `field`.file.
localizer::FloorMaps load_floor_maps(const PlanSource& plan, const std::string& lookup,
                                     const std::function<std::string(const std::string&)>& resolve,
                                     const std::string& field);

}  // namespace fploc::config
