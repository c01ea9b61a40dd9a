// Online drawing-scale correction (issue 12, "estimate a global scale error of the plan online, report
// it, and optionally correct for it"). The plan-change detector (modules/plandiff) estimates over the run
// that the building is (1 + s) times its drawing (plan_diff_t scale_error / scale_sigma); a plan drawn or
// scanned at a slightly wrong scale biases every pose by s times its distance from wherever the drawing
// and the building agree. The correction localizes against the plan scaled by (1 + s) about a centre.
//
// The centre: a pure scale error leaves one point of the drawing where the building has it, and nothing
// the robot measures tells which (a scale about another point is the same plus a translation, which the
// plan alone does not fix). We take the plan's bounding-box centre (FloorPlan::bounds()): it keeps the
// corrected plan's extent centred on the drawing's, so no point moves more than s times half the extent;
// the simulator's scale perturbation uses the same centre (modules/sim perturb.h), so the bench measures
// the correction itself, not a choice of gauge.
//
// When: ScaleCorrection applies an estimate only when it is significant (|s| >= min_error and >=
// min_sigmas sigma: a clean plan, whose estimate is 0 within noise, is never touched) and re-applies
// only when the estimate moved by more than min_change (and change_sigmas sigma) from the applied one, so
// the localizer restarts on a new plan a few times per run at most.
//
// As-built refinement (the same mechanism): the detector also estimates, per wall, how far the building's
// wall stands from the drawn one at each end (plan_diff_t refined_*; each scan's registration error
// eliminated, a prior toward 0 holding the frame); offset_plan() applies them and RefineCorrection says
// when they changed enough to re-build the localization map.
#pragma once
#include <vector>
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>

#include <string>

#include "fploc/floorplan/plan.h"
#include "fploc/matcher/map.h"
#include "fploc/matcher/types.h"

namespace fploc::matcher {

// The point the correction scales about: the centre of the plan's bounding box.
Eigen::Vector2d scale_centre(const FloorPlan& plan);

// The plan scaled by `factor` about `centre` (segments' ends, circles' and arcs' centres and radii;
// element ids, kinds and layers unchanged).
FloorPlan scaled_plan(const FloorPlan& plan, double factor, const Eigen::Vector2d& centre);

// A pose in a plan scaled by f0 -> the same pose in the plan scaled by f1 (both about centre):
// centre + (f1 / f0) (p - centre), heading unchanged.
Pose2 rescaled_pose(const Pose2& p, double f0, double f1, const Eigen::Vector2d& centre);

// The localization map of the plan scaled by (1 + scale_error) about scale_centre(plan), with the given
// look-up ("" = annf-exact; an ANNF is built with its default options, a few hundred ms for a floor).
LocalizationMap scaled_localization_map(const FloorPlan& plan, double scale_error, const std::string& lookup);

struct ScaleCorrectionOptions {
  double min_error = 0.001;   // |s| below this is left alone (0.1 %: 5 mm over 5 m)
  double min_sigmas = 4;      // ... and |s| must be this many sigma
  double min_change = 0.0005; // re-apply when the estimate moved this far from the applied one ...
  double change_sigmas = 2;   // ... and this many sigma
};

// A segment's offset along its left normal at its ends (as-built refinement).
struct SegmentOffset {
  int element = -1;
  double offset_a = 0, offset_b = 0;
};

// The plan with the given segments moved (a + offset_a n, b + offset_b n); ids outside the plan and
// non-segments are ignored.
FloorPlan offset_plan(const FloorPlan& plan, const std::vector<SegmentOffset>& offsets);

struct RefineCorrectionOptions {
  double min_change_m = 0.005;  // re-apply when an end moved this far from the applied offsets ...
  double min_interval_s = 5;    // ... and at least this long after the last (each is a new map and a restart)
};

class RefineCorrection {
 public:
  explicit RefineCorrection(RefineCorrectionOptions o = {}) : o_(o) {}
  // The detector's current offsets at time utime; true when they replace the applied ones.
  bool update(const std::vector<SegmentOffset>& offsets, int64_t utime);
  const std::vector<SegmentOffset>& applied() const { return applied_; }

 private:
  RefineCorrectionOptions o_;
  std::vector<SegmentOffset> applied_;
  int64_t last_utime_ = 0;
  bool have_ = false;
};

// The plan a node localizes against: offsets first (they were measured on the drawing), then the scale.
FloorPlan corrected_plan(const FloorPlan& plan, double scale_error, const std::vector<SegmentOffset>& offsets);
// Its localization map (look-up as scaled_localization_map's).
LocalizationMap corrected_localization_map(const FloorPlan& plan, double scale_error, const std::vector<SegmentOffset>& offsets,
                                           const std::string& lookup);

class ScaleCorrection {
 public:
  explicit ScaleCorrection(ScaleCorrectionOptions o = {}) : o_(o) {}
  // The detector's current estimate (sigma <= 0 or non-finite: nothing to tell yet). Returns the scale
  // error to correct for from now on (0: none) when it changes, nullopt when the applied one stays.
  std::optional<double> update(double error, double sigma);
  double applied() const { return applied_; }  // the scale error currently corrected for (0: none)

 private:
  ScaleCorrectionOptions o_;
  double applied_ = 0;
};

// Both live corrections of a one-floor plan from the plan diff, as the matcher and optimizer apply them:
// the drawing scale (plan_diff_scale) and the as-built wall offsets (plan_diff_refine).
class PlanCorrection {
 public:
  PlanCorrection(bool scale, bool refine) : scale_on_(scale), refine_on_(refine) {}
  bool enabled() const { return scale_on_ || refine_on_; }
  // A new diff estimate. Returns the localization map of the corrected plan when the correction changed
  // (nullptr when it stays); `said` then describes it ("plan corrected: scale ...").
  std::unique_ptr<LocalizationMap> update(const FloorPlan& plan, double scale_error, double scale_sigma,
                                          const std::vector<SegmentOffset>& offsets, int64_t utime,
                                          const std::string& lookup, std::string* said);
  double scale() const { return scale_.applied(); }  // the scale error corrected for now (0: none)

 private:
  bool scale_on_, refine_on_;
  ScaleCorrection scale_;
  RefineCorrection refine_;
};

}  // namespace fploc::matcher
