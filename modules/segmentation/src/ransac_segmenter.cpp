#include "fploc/segmentation/ransac_segmenter.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>

namespace fploc::seg {

RansacSegmenter::RansacSegmenter(SegmenterConfig cfg, int max_iterations, int subsample)
    : Segmenter(cfg), max_iterations_(max_iterations), subsample_(std::max(1, subsample)) {}

bool RansacSegmenter::fit_plane(const Candidates& c, const Eigen::Vector3d& up_in, const Eigen::Vector4d*,
                                Eigen::Vector4d& plane) {
  const Eigen::Vector3f up = up_in.normalized().cast<float>();
  // Only points above the sensor along the prior can be the ceiling (below, for the flipped ground).
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(c.p.size() / subsample_ + 1);
  for (size_t i = 0; i < c.p.size(); i += subsample_) {
    const Eigen::Vector3f& p = c.p[i];
    if (up.dot(p) < 0.2f) continue;
    cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  if (cloud->size() < 10) return false;
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);  // plane perpendicular to `axis` (normal ~ axis)
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setAxis(up);
  seg.setEpsAngle(cfg_.max_tilt_deg * M_PI / 180.0);
  seg.setDistanceThreshold(cfg_.inlier_threshold_m);
  seg.setMaxIterations(max_iterations_);
  seg.setInputCloud(cloud);
  pcl::PointIndices inliers;
  pcl::ModelCoefficients coeffs;
  // SACSegmentation seeds its sampler deterministically (fixed seed), so results are reproducible.
  seg.segment(inliers, coeffs);
  if (coeffs.values.size() != 4 || inliers.indices.size() < 3) return false;
  Eigen::Vector4d pl(coeffs.values[0], coeffs.values[1], coeffs.values[2], coeffs.values[3]);
  const double nn = pl.head<3>().norm();
  if (!(nn > 0) || !pl.allFinite()) return false;
  pl /= nn;
  if (pl.head<3>().dot(up_in) > 0) pl = -pl;  // normal into the room (against `up`)
  plane = pl;
  return true;
}

}  // namespace fploc::seg
