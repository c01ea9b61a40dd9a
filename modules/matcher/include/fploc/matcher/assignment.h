// A feature point's correspondence candidates (target ids of a NearestLookup). No Ceres here: the
// optimizer keeps these in its header.
#pragma once
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
  bool operator==(const Assignment& o) const {
    if (point != o.point || n != o.n) return false;
    for (int i = 0; i < n; ++i)
      if (cand[i] != o.cand[i] || w[i] != o.w[i]) return false;
    return true;
  }
};

struct AssignOptions {
  double gate_m = 1.0;     // points farther than this from all candidates are left out
  bool group_rule = true;  // one PCA group <-> one element (element look-ups only)
  int max_candidates = kMaxCandidates;
  int stride = 1;          // use every stride-th point (1 = all)
  // Per plan element (target id of an element look-up): its weight in the floor-plan terms, e.g. from
  // the plan-change detector (element_weights.h). Elements with weight <= 0 are no candidates at all;
  // null (or a look-up of point targets): every element 1. Not owned.
  const std::vector<float>* element_weight = nullptr;
};

}  // namespace fploc::matcher