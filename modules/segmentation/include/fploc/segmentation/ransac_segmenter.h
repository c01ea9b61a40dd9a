// The swappable baseline: the same Segmenter (outputs, fallbacks, wall selection) with the plane fit done
// by PCL's RANSAC (RansacPlaneFit). PCL stays inside ransac_plane_fit.cpp.
#pragma once
#include "fploc/segmentation/ransac_plane_fit.h"
#include "fploc/segmentation/segmenter.h"

namespace fploc::seg {

class RansacSegmenter : public Segmenter {
 public:
  explicit RansacSegmenter(SegmenterConfig cfg, int max_iterations = 200, int subsample = 2)
      : Segmenter(cfg, std::make_unique<RansacPlaneFit>(cfg, max_iterations, subsample)) {}
};

}  // namespace fploc::seg
