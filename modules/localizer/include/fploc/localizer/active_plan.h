// The plan a node's Localizer registers against: a building's floor maps, the floor in use, the
// plan-change detector's per-element weights for that floor's plan, and the plan correction (drawing
// scale / as-built refinement from the diff, matcher/plan_scale.h). The matcher and optimizer nodes each
// hold one; when the floor or the corrected map changes they ask it for a new Localizer.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fploc/localizer/floor_maps.h"
#include "fploc/localizer/localizer.h"
#include "fploc/matcher/element_weights.h"
#include "fploc/matcher/plan_scale.h"

namespace fploc::localizer {

class ActivePlan {
 public:
  ActivePlan() = default;
  // diff_weight: the weight of elements the diff marks missing or moved (0: left out); lookup: the
  // look-up a corrected plan's map is built with (as the option `lookup`).
  ActivePlan(FloorMaps floors, float diff_weight, matcher::PlanCorrection correction, std::string lookup);

  const FloorMaps& floors() const { return floors_; }
  bool multi_floor() const { return floors_.multi_floor(); }
  int floor() const { return floor_; }
  const std::string& floor_name() const { return floors_.building->floors[size_t(floor_)].name; }
  const FloorPlan& plan() const { return *floors_.maps[size_t(floor_)].plan; }  // as drawn (uncorrected)

  // A Localizer on the map in use (the floor's, or the corrected plan's), cfg's element weights pointing
  // at this floor's weights. The previous Localizer must not be used any more.
  std::unique_ptr<Localizer> make_localizer(Config cfg) const;
  // Another floor: its elements start unflagged (a diff's flags are for one plan).
  void set_floor(int floor);
  // A diff's flagged elements (ids of the plan in use). False, with *error, when one is not in the plan
  // (a diff of another plan): nothing changes then.
  bool apply_flags(const std::vector<matcher::FlaggedElement>& flagged, std::string* error);
  // A diff's scale / as-built estimate. True when the corrected map changed (make a new Localizer), with
  // *said describing it. For a building of several floors there is no correction: false, and *error the
  // first time.
  bool correct(double scale_error, double scale_sigma, const std::vector<matcher::SegmentOffset>& offsets, int64_t utime,
               std::string* said, std::string* error);
  bool correcting() const { return correction_.enabled(); }
  double scale() const { return correction_.scale(); }  // the scale error corrected for now (0: none)

 private:
  FloorMaps floors_;
  int floor_ = 0;
  float diff_weight_ = 0;
  matcher::PlanCorrection correction_{false, false};
  std::string lookup_;
  bool warned_ = false;
  // The current and the previous weights and corrected map: a Localizer made before the last change may
  // still point at them until the node replaces it.
  std::unique_ptr<matcher::ElementWeights> weights_, previous_weights_;
  std::unique_ptr<matcher::LocalizationMap> corrected_, previous_corrected_;
};

}  // namespace fploc::localizer
