#include "fploc/config/plandiff.h"

#include "fploc/config/check.h"

namespace fploc::config {

PlanDiffSettings config_of(const PlanDiffOptions& o) {
  PlanDiffSettings s;
  if (given(o.min_frames(), "plan_diff", "min_frames")) s.diff.min_frames = o.min_frames();
  if (given(o.moved_min_m(), "plan_diff", "moved_min_m")) s.diff.moved_min_m = o.moved_min_m();
  if (given(o.max_range_m(), "plan_diff", "max_range_m")) s.diff.max_range_m = o.max_range_m();
  if (given(o.new_min_height_m(), "plan_diff", "new_min_height_m")) s.diff.new_min_height_m = o.new_min_height_m();
  if (o.no_height_check()) s.diff.new_min_height_m = 0;
  if (given(o.publish_hz(), "plan_diff", "publish_hz")) s.publish_hz = o.publish_hz();
  if (given(o.frame_hz(), "plan_diff", "frame_hz")) s.frame_hz = o.frame_hz();
  return s;
}

}  // namespace fploc::config
