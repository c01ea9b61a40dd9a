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
  // The drawing scale's share of a published pose's uncertainty. A scale error s left in the plan moves a
  // pose by s (p - c) (c = matcher::scale_centre, the point the correction and the simulator scale about), the
  // same on every frame, so the window's fit cannot see it. From the diff's latest estimate (correct() keeps
  // it, whether or not the correction is on): s^2 is estimated by (estimate - applied)^2 - sigma^2, floored at
  // 0 (an unbiased estimate of a square: E[estimate^2] = s^2 + sigma^2), so a plan drawn to scale adds ~0 and
  // one off by 0.5 % the spread its error has. Added to x/y as s^2 (p - c)(p - c)^T; published only (like
  // Config::map_sigma_m, the gates keep the fit's own covariance). Nothing before the first estimate, nor
  // for a building of several floors (no scale estimate is used there).
  void add_scale_error(Pose* pose) const { add_scale_error(pose, unexplained_scale_squared()); }
  double unexplained_scale_squared() const;
  // The same with a given s^2 (the poses a correction makes final were estimated before it).
  void add_scale_error(Pose* pose, double s2) const;

 private:
  FloorMaps floors_;
  int floor_ = 0;
  float diff_weight_ = 0;
  matcher::PlanCorrection correction_{false, false};
  std::string lookup_;
  bool warned_ = false;
  double scale_estimate_ = 0, scale_sigma_ = 0;  // the diff's latest (sigma 0: none yet)
  Eigen::Vector2d scale_centre_ = Eigen::Vector2d::Zero();  // matcher::scale_centre of the floor's plan
  // The current and the previous weights and corrected map: a Localizer made before the last change may
  // still point at them until the node replaces it.
  std::unique_ptr<matcher::ElementWeights> weights_, previous_weights_;
  std::unique_ptr<matcher::LocalizationMap> corrected_, previous_corrected_;
};

}  // namespace fploc::localizer
