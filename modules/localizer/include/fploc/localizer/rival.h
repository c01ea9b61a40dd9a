// Two fits of one frame compared point by point (the second fit of a re-acquisition, UncertaintyConfig::rival_*).
//
// A re-acquisition's fix (the start from a given pose, after LOST) is the registration that explains the most points,
// but where the building holds what the plan does not (a run of shelves along a wall, a cabinet on a drawn line) a wrong
// pose can explain more points than the right one: at the wrong pose the shelf faces lie on the wall behind them, at
// the right one they are clutter in front of it. Counting points cannot tell these apart; what can tell a second fit
// that is merely worse from one that is another explanation of the same scan is what each explains that the other
// does not:
//   gained  points the second fit puts on the plan that the fix leaves off it (the second fit explains structure the
//           fix cannot: were the fix right, that structure would be something not drawn)
//   lost    points the fix puts on the plan that the second fit leaves off it
//   lost_behind  of the lost points, those that from the second fit's sensor position lie beyond a drawn wall (the ray
//           to the point crosses a plan segment more than the inlier distance before it). Clutter stands in front of
//           walls; a point seen through a wall contradicts the second fit (a pose slid towards a shelved wall puts the
//           opposite wall's points behind that wall).
//   gained_hidden  of the gained points, those on a face that a drawn wall hides from the second fit's sensor (the same
//           see-through test): a thick wall's outer face cannot be what the sensor saw from inside the room. A wall
//           built 0.2 m in from where the plan draws it is explained by the wall's outer face 0.45 m on, at a pose
//           0.45 m off (a hand-written room world published POOR for 25 s while 1 cm off); they are no structure.
// A second fit is another explanation when it gains structure (gained_structure >= min_gained: that many points on one
// drawn element, not a scatter of chance hits across the plan) and what it loses could stand in
// front of the plan (lost_behind <= max_behind_share of lost). A second fit that only loses points (a pose slid along
// a corridor away from its end wall: the wall's points become clutter, nothing is gained) is no rival however many
// points it keeps. With point targets (the k-d tree look-up) each sample is its own element and hides nothing: the
// test seldom finds structure there. The see-through test walks every plan segment per lost point (a frame's few
// hundred, on the few frames of a confirmation); a plan of thousands of segments would want a grid for it.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "fploc/core/feature_frame.h"
#include "fploc/core/pose.h"
#include "fploc/matcher/lookup.h"

namespace fploc::localizer {

struct FitComparison {
  int points = 0;       // points compared (every stride-th)
  int fix_inliers = 0;  // within inlier_m of the plan at the fix
  int rival_inliers = 0;
  int gained = 0;       // inliers at the rival, not at the fix
  int gained_hidden = 0;     // of them, on a drawn face another drawn wall hides from the rival's sensor
  int gained_structure = 0;  // the most of the others on one plan element (a wall, a jamb: structure, not chance hits)
  int lost = 0;         // inliers at the fix, not at the rival
  int lost_behind = 0;  // lost points beyond a drawn segment seen from the rival
};

// Points of f (sensor frame, the sensor at the pose's origin) at both poses; every stride-th point.
FitComparison compare_fits(const matcher::NearestLookup& lookup, const FeatureFrame& f, const Pose2& fix, const Pose2& rival,
                           double inlier_m, int stride = 1);

// Whether the segment from `from` to `to` (plan frame) crosses a plan segment more than margin_m before `to`.
// Point targets and arcs/circles are not walls here (they never hide a point).
bool seen_through_plan(const std::vector<matcher::TargetGeom>& geometry, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                       double margin_m);

}  // namespace fploc::localizer
