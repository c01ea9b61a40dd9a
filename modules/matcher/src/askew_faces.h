// Askew faces (AssignOptions::askew_max_m, select_points in plan_terms.cpp): the points that lie along a plan
// segment on a line askew to it (a cabinet's face where a glass wall is drawn) are left out of a frame.
#pragma once
#include <vector>

#include "fploc/matcher/assignment.h"
#include "fploc/matcher/lookup.h"
#include "fploc/matcher/types.h"

namespace fploc::matcher {

// The points (on: each point's closest element within the gate, -1 none) of the runs that lie on a line askew to
// their element (AssignOptions::askew_max_m): per segment, its points in runs along it (a gap of more than
// kRunGapM ends a run: a cabinet's face, a stretch of the wall itself, a person in front of it are runs of their
// own); per run, the line most of its points lie on (Theil-Sen: the median of the pairwise slopes over up to
// kSample of them, spread evenly) and the least-squares slope of that line's inliers with its variance; its turn
// over the segment's whole length, d = slope x length, is what the run's line makes of the wall's end offsets.
// The guess's own yaw error turns every run alike: the point-weighted median slope of the runs of >=
// kMinYawPoints points is taken out first. A run is askew when what is left exceeds about askew_max_m * sqrt(2),
// counting the slope's own uncertainty (chi-square, 1 dof, 99 %): its points get drop[i] = 1.
void askew_points(const std::vector<TargetGeom>& g, const FeatureFrame& f, const Pose2& x, const std::vector<int>& on,
                  const AssignOptions& o, std::vector<char>* drop);

}  // namespace fploc::matcher
