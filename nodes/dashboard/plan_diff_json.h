// plan_diff_t -> the dashboard's "plan_diff" stream: {"utime", "frames", "seen", "missing", "moved",
// "unobserved", "scale_error", "scale_sigma", "items": [{"kind": "missing"|"moved"|"new", "element", "circle", "x0", "y0", "x1", "y1", "offset_m"}]}.
#pragma once
#include <fploc/plan_diff_t.hpp>

#include <string>

namespace fploc::dashboard {
std::string plan_diff_json(const fploc::plan_diff_t& m);
}
