// The localization map a node loads: the floor plan, the ANNF when the look-up needs one, and the
// selected correspondence look-up. Look-up names: "annf-exact" (default), "annf-paper" (the leaf's two
// stored candidates, the closer one used), "annf-paper-first" (only the leaf's first element),
// "kdtree" (points sampled on the plan), "brute-force". A plan loaded from an occupancy map (map_server
// .yaml) also keeps the map's free space (floorplan/free_space.h), which the published status checks, and
// its cell's position error (map_sigma_m), which the published covariance adds.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "fploc/floorplan/free_space.h"
#include "fploc/floorplan/plan.h"
#include "fploc/matcher/lookup.h"

namespace fploc::annf {
class Annf;
}  // namespace fploc::annf

namespace fploc::matcher {

struct LocalizationMap {
  std::shared_ptr<const FloorPlan> plan;
  std::shared_ptr<const annf::Annf> annf;  // null unless an ANNF look-up is used
  std::unique_ptr<NearestLookup> lookup;
  std::shared_ptr<const FreeSpace> free_space;  // null unless the plan is an occupancy map
  // The plan's own position error that every point of a frame shares, so that it does not average out over
  // them: for an occupancy map a wall lies somewhere in its cell, resolution / sqrt(12) (a uniform position
  // within the cell); 0 for a drawn plan (its accuracy is unknown; CovarianceConfig::plan_sigma_m sets one).
  double map_sigma_m = 0;
  std::string note;                  // what was loaded/built (for logs)
};

// What a plan loaded from path keeps beside its elements when path is an occupancy map (a map_server .yaml /
// .yml): its free space and map_sigma_m. Nothing for any other file. load_localization_map calls it, and so
// does every loader of a plan file (a building's floors).
void add_occupancy_extras(LocalizationMap& m, const std::string& path);

// Known look-up names.
const std::vector<std::string>& lookup_names();

// From a plan already in memory. The ANNF (if needed) is built with its default options (depth 7,
// 6 m root fields). Throws std::runtime_error on an unknown name or an empty plan.
LocalizationMap make_localization_map(FloorPlan plan, const std::string& lookup = "annf-exact");
// From a file: a plan (.dxf/.csv/.json, layers/units as fploc/floorplan/io.h) or a built .fpmap (its
// ANNF is used when its mode matches the look-up, else one is built from its plan).
LocalizationMap load_localization_map(const std::string& path, const std::vector<std::string>& layers,
                                      const std::string& units, const std::string& lookup = "annf-exact");

}  // namespace fploc::matcher