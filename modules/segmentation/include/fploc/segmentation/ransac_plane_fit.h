// The swappable baseline plane fit: PCL's RANSAC (pcl::SACSegmentation, SACMODEL_PERPENDICULAR_PLANE around
// the gravity prior; planes extracted one after another until one passes the "rays end there" test, up to
// 4). PCL stays inside ransac_plane_fit.cpp.
#pragma once
#include "fploc/segmentation/plane_fit.h"

namespace fploc::seg {

class RansacPlaneFit : public PlaneFit {
 public:
  RansacPlaneFit(const SegmenterConfig& cfg, int max_iterations = 200, int subsample = 2);
  const char* name() const override { return "ransac"; }
  bool fit(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous, PlaneRole role,
           Eigen::Vector4d& plane) override;

 private:
  SegmenterConfig cfg_;
  int max_iterations_;
  int subsample_;
};

}  // namespace fploc::seg
