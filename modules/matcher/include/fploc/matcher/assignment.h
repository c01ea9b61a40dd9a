// A feature point's correspondence candidates (target ids of a NearestLookup). No Ceres here: the
// optimizer keeps these in its header.
#pragma once

namespace fploc::matcher {

constexpr int kMaxCandidates = 8;

struct Assignment {
  int point = -1;
  int n = 0;
  int cand[kMaxCandidates] = {};
  bool operator==(const Assignment& o) const {
    if (point != o.point || n != o.n) return false;
    for (int i = 0; i < n; ++i)
      if (cand[i] != o.cand[i]) return false;
    return true;
  }
};

struct AssignOptions {
  double gate_m = 1.0;     // points farther than this from all candidates are left out
  bool group_rule = true;  // one PCA group <-> one element (element look-ups only)
  int max_candidates = kMaxCandidates;
  int stride = 1;          // use every stride-th point (1 = all)
};

}  // namespace fploc::matcher