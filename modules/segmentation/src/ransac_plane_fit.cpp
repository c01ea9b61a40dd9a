#include "fploc/segmentation/ransac_plane_fit.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "segmenter_constants.h"

namespace fploc::seg {

RansacPlaneFit::RansacPlaneFit(const SegmenterConfig& cfg, int max_iterations, int subsample)
    : cfg_(cfg), max_iterations_(max_iterations), subsample_(std::max(1, subsample)) {}

bool RansacPlaneFit::fit(const Candidates& c, const Eigen::Vector3d& up_in, const Eigen::Vector4d*, PlaneRole,
                         Eigen::Vector4d& plane) {
  const Eigen::Vector3f up = up_in.normalized().cast<float>();
  // Only points above the sensor along the prior can be the ceiling (below, for the flipped ground).
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(c.p.size() / subsample_ + 1);
  for (size_t i = 0; i < c.p.size(); i += subsample_) {
    const Eigen::Vector3f& p = c.p[i];
    if (up.dot(p) < k::kMinSeedHeightM) continue;
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
  // Sequential extraction: RANSAC's largest horizontal plane is often a band through the walls at one
  // height (in a corridor, or just above the sensor); a ceiling is where the rays end, so a plane with more
  // returns beyond it than max_beyond_ratio x its inliers (the acceptance test of Segmenter) is removed from
  // the cloud and the next largest is tried, up to max_planes.
  constexpr int kMaxPlanes = 4;
  const float thr = float(cfg_.inlier_threshold_m);
  bool have = false;
  for (int round = 0; round < kMaxPlanes && cloud->size() >= 10; ++round) {
    seg.setInputCloud(cloud);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coeffs;
    // SACSegmentation seeds its sampler deterministically (fixed seed), so results are reproducible.
    seg.segment(inliers, coeffs);
    if (coeffs.values.size() != 4 || inliers.indices.size() < 3) break;
    Eigen::Vector4d pl(coeffs.values[0], coeffs.values[1], coeffs.values[2], coeffs.values[3]);
    const double nn = pl.head<3>().norm();
    if (!(nn > 0) || !pl.allFinite()) break;
    pl /= nn;
    if (pl.head<3>().dot(up_in) > 0) pl = -pl;  // normal into the room (against `up`)
    if (!have) plane = pl;  // the largest plane, if none passes
    have = true;
    // Where the rays end? (all candidates, as Segmenter::quality counts them)
    const Eigen::Vector3f n = pl.head<3>().cast<float>();
    const float d = float(pl[3]);
    int in = 0, beyond = 0;
    for (const auto& p : c.p) {
      const float r = n.dot(p) + d;
      in += std::abs(r) < thr;
      beyond += r < -2 * thr;
    }
    if (beyond <= cfg_.max_beyond_ratio * in) {
      plane = pl;
      return true;
    }
    // Remove this plane's inliers and try the next one.
    pcl::PointCloud<pcl::PointXYZ>::Ptr rest(new pcl::PointCloud<pcl::PointXYZ>);
    rest->reserve(cloud->size() - inliers.indices.size());
    std::vector<uint8_t> is_in(cloud->size(), 0);
    for (int i : inliers.indices) is_in[size_t(i)] = 1;
    for (size_t i = 0; i < cloud->size(); ++i)
      if (!is_in[i]) rest->push_back((*cloud)[i]);
    cloud = rest;
  }
  return have;  // the largest plane (the acceptance test rejects it with the reason)
}

}  // namespace fploc::seg
