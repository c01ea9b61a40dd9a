// The swappable baseline: the same Segmenter (outputs, fallbacks, wall selection) with the plane fit done
// by PCL's RANSAC (pcl::SACSegmentation, SACMODEL_PERPENDICULAR_PLANE around the gravity prior; planes
// extracted one after another until one passes the "rays end there" test, up to 4).
// PCL stays inside ransac_segmenter.cpp.
#pragma once
#include "fploc/segmentation/segmenter.h"

namespace fploc::seg {

class RansacSegmenter : public Segmenter {
 public:
  explicit RansacSegmenter(SegmenterConfig cfg, int max_iterations = 200, int subsample = 2);
  const char* name() const override { return "ransac"; }

 protected:
  bool fit_plane(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous,
                 Eigen::Vector4d& plane) override;

 private:
  int max_iterations_;
  int subsample_;
};

}  // namespace fploc::seg
