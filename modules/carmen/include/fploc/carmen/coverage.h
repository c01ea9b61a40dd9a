// Which scans of a CARMEN log a map built from a prefix of the same log covers, and the split rule of the
// non-circular protocol (`fploc import-carmen --map-end auto`, `fploc bench real`).
//
// A return of a scan is covered by a set of scans when, at the reference poses, it lies within radius_m of a
// cell hit by a return of that set; a scan is covered when at least covered_ratio of its returns are (the
// same 50 % share that fploc-grid2d needs to accept a fit). prefix_coverage() gives, for every scan k, the
// smallest prefix length S (scans [0, S)) that covers it, in one pass: every cell remembers the first scan
// whose return hit within radius_m of it, and scan k is covered by [0, S) iff its ceil(covered_ratio * n)-th
// smallest "first scan" is < S.
//
// Split rule (choose_split): the smallest S in {min_fraction, min_fraction + step, ..., max_fraction} * N
// whose prefix covers at least covered_share of the remaining scans [S, N); if none does, the S (of those
// candidates) with the largest covered share. The same rule and values for every log.
#pragma once
#include <cstddef>
#include <vector>

#include "fploc/carmen/carmen.h"

namespace fploc::carmen {

struct CoverageConfig {
  double resolution = 0.05;
  double radius_m = 0.1;       // a return within this of a mapped hit is covered (grid2d's inlier distance)
  double covered_ratio = 0.5;  // share of a scan's returns that must be covered (grid2d's min_inlier_ratio)
  double min_range_m = 0.1, max_range_m = 40.0;  // returns used (grid2d's range limits)
  float no_return = 1e30f;     // ranges >= this are no return
};

// first_cover[k] = smallest S such that scans [0, S) cover scan k (<= k + 1 unless scan k has too few
// returns of its own; scans.size() + 1 when no prefix covers it).
std::vector<size_t> prefix_coverage(const std::vector<LaserRecord>& scans, const CoverageConfig& cfg);

struct SplitRule {
  double min_fraction = 0.2, max_fraction = 0.8, step = 0.05;
  double covered_share = 0.75;
};
struct Split {
  size_t split = 0;           // map from scans [0, split), localize [split, N)
  double fraction = 0;        // split / N (one of the candidates)
  double covered_share = 0;   // share of [split, N) covered by [0, split)
  bool met = false;           // covered_share >= rule.covered_share
};
Split choose_split(const std::vector<size_t>& first_cover, const SplitRule& rule);

// Share of each scan's returns (scans [b, e)) within radius_m of an occupied cell of g, at the reference poses.
std::vector<double> grid_coverage(const Grid& g, const std::vector<LaserRecord>& scans, size_t b, size_t e,
                                  const CoverageConfig& cfg);

}  // namespace fploc::carmen
