// The plan diff's as-built refinement (Diff::refined): per scan, each well-seen wall's median offset is
//   (1 - t) o_a + t o_b + c . (bx, by, byaw),
// t where along the wall the scan saw it, o_a / o_b the wall's offsets at its ends and c how the scan's
// registration error moves the wall's points along its normal. The scan's error is eliminated (Schur
// complement) and the normal equations in the ends' offsets are summed over the run; the result solves them
// with a prior toward 0 that holds the gauge.
#pragma once
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace fploc::plandiff {

// The plan refined to the building (as built): segment `element` offset along its left normal by
// offset_a at its end a and offset_b at b. The frame is that of the whole plan (the per-scan registration
// error is eliminated, the prior holds the gauge: the offsets are as small as the data allow).
struct RefinedSegment {
  int element = -1;
  double offset_a = 0, offset_b = 0;
  int frames = 0;  // scans that observed it
};

class WallRefinement {
 public:
  explicit WallRefinement(size_t elements);
  struct Observation {
    int element;
    double t, offset;
    Eigen::Vector3d c;
  };
  // One scan's observations (fewer than 4, or a scan whose error they do not fix, add nothing).
  void add_scan(const std::vector<Observation>& obs);

  struct Options {
    double obs_sigma_m, prior_m, min_info;
    bool ends;
    int min_frames;
  };
  // The segments observed in >= min_frames scans: each end's offset where both ends are observed well enough
  // (ends), else the mean offset at both, else nothing.
  std::vector<RefinedSegment> result(const Options& o) const;

 private:
  Eigen::MatrixXd H_;  // normal equations in (o_a, o_b) per segment, scans eliminated
  Eigen::VectorXd g_;
  std::vector<int> frames_;
};

}  // namespace fploc::plandiff
