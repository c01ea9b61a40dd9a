// A feature point's correspondence candidates (target ids of a NearestLookup). No Ceres here: the
// optimizer keeps these in its header.
#pragma once
#include <cstddef>
#include <vector>

namespace fploc::matcher {

constexpr int kMaxCandidates = 8;

struct Assignment {
  int point = -1;
  int n = 0;
  int cand[kMaxCandidates] = {};
  // Per candidate: the element's weight (AssignOptions::element_weight; 1 without). The residual of the
  // point is scaled by the weight of the candidate that is closest when it is evaluated.
  float w[kMaxCandidates] = {1, 1, 1, 1, 1, 1, 1, 1};
  // The point's sampling weight (AssignOptions::element_quota): 1 for a point taken as every stride-th
  // point (it stands for stride points), 1/sqrt(stride) for a point kept for sure because its element has
  // few points in the frame (it stands for itself), so that the kept points' squared residuals, summed
  // with these weights and times stride, estimate the sum over all points (Horvitz-Thompson). It scales
  // the point's residual only, not the as-built model's offset prior of its element.
  float sw = 1;
  bool operator==(const Assignment& o) const {
    if (point != o.point || n != o.n || sw != o.sw) return false;
    for (int i = 0; i < n; ++i)
      if (cand[i] != o.cand[i] || w[i] != o.w[i]) return false;
    return true;
  }
};

// The point budget's stride: every `stride`-th point, or more sparsely so that at most about max_points of the
// frame's `points` are used (max_points <= 0: no budget). The matcher, the window optimizer and the Localizer's
// fit comparisons all take their points this way.
inline int budget_stride(size_t points, int stride, int max_points) {
  int s = stride > 1 ? stride : 1;
  if (max_points > 0 && points > size_t(max_points) * size_t(s)) s = int((points + size_t(max_points) - 1) / size_t(max_points));
  return s;
}

// A point of the frame that the assignments use, with its sampling weight (Assignment::sw).
struct SampledPoint {
  int point = -1;
  float sw = 1;
  bool operator==(const SampledPoint& o) const { return point == o.point && sw == o.sw; }
};

struct AssignOptions {
  double gate_m = 1.0;     // points farther than this from all candidates are left out
  bool group_rule = true;  // one PCA group <-> one element (element look-ups only)
  int max_candidates = kMaxCandidates;
  int stride = 1;          // use every stride-th point (1 = all)
  // Per-element point budget (element look-ups, stride > 1): the points whose closest candidate within the
  // gate is an element that holds at most element_quota of the frame's points are all kept (the stride
  // applies to the other elements' points), with sampling weight Assignment::sw = 1/sqrt(stride). A wall
  // seen with a handful of points (the only one across a corridor, far away) keeps them all, where every
  // stride-th would keep 0-2 of them. 0 = off (every stride-th point of the frame).
  int element_quota = 0;
  // Faces askew to their element (element look-ups): the points whose closest candidate within the gate is a
  // segment, in a run along it (a gap of more than 0.5 m ends a run) that lies on a line turning against the
  // segment by more than about askew_max_m * sqrt(2) between its two ends (beyond that line's own uncertainty at
  // askew_point_sigma_m per point, and after the turn every run shows alike, the guess's own yaw error), are left
  // out: a cabinet's face seen where a glass wall is drawn, askew to it, is not that wall, and as a wall (the
  // as-built model gives every wall a share) it holds the pose against the walls that are there. A wall standing a
  // few centimetres off its drawn place, or moved along its normal, turns by no more than its ends' offsets; a
  // person in front of a wall is a run of its own, too short to turn significantly. Judged at the pose the points
  // are selected at (select_points): a tracking guess. 0 = off.
  double askew_max_m = 0;
  double askew_point_sigma_m = 0.04;
  // The points to use, as select_points (plan_terms.h) chose them: when given, stride, element_quota and
  // askew_max_m are not looked at (a caller that assigns one frame many times at nearby poses selects once). Not owned.
  const std::vector<SampledPoint>* points = nullptr;
  // Per plan element (target id of an element look-up): its weight in the floor-plan terms, e.g. from
  // the plan-change detector (element_weights.h). Elements with weight <= 0 are no candidates at all;
  // null (or a look-up of point targets): every element 1. Not owned.
  const std::vector<float>* element_weight = nullptr;
};

}  // namespace fploc::matcher