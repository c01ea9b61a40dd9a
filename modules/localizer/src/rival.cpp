#include "fploc/localizer/rival.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "fploc/core/segment2d.h"
#include "fploc/matcher/assignment.h"
#include "fploc/matcher/plan_terms.h"
#include "fploc/matcher/types.h"

namespace fploc::localizer {

namespace {
// Squared distance from p to the nearest of the lookup's candidate targets (as evaluate_fit measures it), and which.
double nearest2(const matcher::NearestLookup& lookup, const std::vector<matcher::TargetGeom>& g, const Eigen::Vector2d& p,
                int* which) {
  int cand[matcher::kMaxCandidates];
  const int n = lookup.candidates(p, cand, matcher::kMaxCandidates);
  double best = std::numeric_limits<double>::infinity();
  *which = -1;
  Eigen::Vector2d q;
  for (int i = 0; i < n; ++i) {
    const double d = matcher::closest_of(g, cand + i, 1, p, &q, nullptr);
    if (d * d < best) best = d * d, *which = cand[i];
  }
  return best;
}
}  // namespace

bool seen_through_plan(const std::vector<matcher::TargetGeom>& geometry, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                       double margin_m) {
  const Eigen::Vector2d r = to - from;
  const double len = r.norm();
  if (!(len > margin_m)) return false;
  // Crossings on the ray short of margin_m before `to` hide the point.
  const Eigen::Vector2d short_of = from + r * ((len - margin_m) / len);
  for (const matcher::TargetGeom& t : geometry)
    if (t.kind == ElementKind::kSegment && t.len > 0 && segments_cross(from, short_of, t.a, t.b)) return true;
  return false;
}

FitComparison compare_fits(const matcher::NearestLookup& lookup, const FeatureFrame& f, const Pose2& fix, const Pose2& rival,
                           double inlier_m, int stride) {
  FitComparison c;
  const auto& g = lookup.geometry();
  const double in2 = inlier_m * inlier_m;
  const Eigen::Vector2d sensor(rival.x, rival.y);
  const size_t st = size_t(std::max(1, stride));
  std::unordered_map<int, int> gained_on;  // gained points per plan element
  for (size_t i = 0; i < f.points.size(); i += st) {
    ++c.points;
    const Eigen::Vector2d pf = matcher::transform(fix, f.points[i].p), pr = matcher::transform(rival, f.points[i].p);
    int ef = -1, er = -1;
    const bool at_fix = nearest2(lookup, g, pf, &ef) <= in2, at_rival = nearest2(lookup, g, pr, &er) <= in2;
    c.fix_inliers += at_fix;
    c.rival_inliers += at_rival;
    if (at_rival && !at_fix) {
      ++c.gained;
      // A drawn face that another drawn wall hides from the rival's sensor (a thick wall's outer face seen from inside
      // the room) is not what the sensor saw: it explains nothing.
      if (seen_through_plan(g, sensor, pr, inlier_m))
        ++c.gained_hidden;
      else if (er >= 0)
        c.gained_structure = std::max(c.gained_structure, ++gained_on[er]);
    }
    if (at_fix && !at_rival) {
      ++c.lost;
      if (seen_through_plan(g, sensor, pr, inlier_m)) ++c.lost_behind;
    }
  }
  return c;
}

}  // namespace fploc::localizer
