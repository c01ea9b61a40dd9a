// frame_pose_t <-> localizer::FramePose (the SFR step's result). Pure mappings.
#pragma once
#include <fploc/frame_pose_t.hpp>

#include "fploc/localizer/localizer.h"

namespace fploc::adapters {

// solve_ms is the caller's (wall-clock, 0 in replay).
frame_pose_t to_msg(const localizer::FramePose& f, int64_t seq, double solve_ms);
// A non-finite twist becomes zero, an unknown status LOST.
localizer::FramePose from_msg(const frame_pose_t& m);

}  // namespace fploc::adapters
