// A fix against the free space of an occupancy-map plan (floorplan/free_space.h): of the frame's points at pose
// x that the map has an opinion about -- those on the plan (inlier_ratio of all, from evaluate_fit) and those on
// its empty floor (farther than clearance_m from any occupied cell) -- the share on empty floor. Points in unknown
// space or off the map count for neither (a room the map saw in part does not contradict it). 0 when no point
// counts.
#pragma once
#include "fploc/core/feature_frame.h"
#include "fploc/core/pose.h"
#include "fploc/floorplan/free_space.h"

namespace fploc::matcher {

double contradicted_share(const FreeSpace& free_space, const FeatureFrame& f, const Pose2& x, double clearance_m,
                          double inlier_ratio);

}  // namespace fploc::matcher
