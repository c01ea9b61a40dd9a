#include "fploc/ndt/ndt_localizer.h"

#include <pcl/common/transforms.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/ndt.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fploc::ndt {

namespace {
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// PCL's NDT with its Hessian at a given transform exposed (computeHessian is protected); the
// derivatives are PCL's own (Magnusson 2009, eq. 6.13).
class HessianNdt : public pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  Eigen::Matrix<double, 6, 6> hessian_at(const Eigen::Matrix4f& T) {
    Cloud moved;
    pcl::transformPointCloud(*input_, moved, T);
    Eigen::Matrix<double, 6, 1> p;
    float x, y, z, r, pi, ya;
    pcl::getTranslationAndEulerAngles(Eigen::Affine3f(T), x, y, z, r, pi, ya);
    p << x, y, z, r, pi, ya;
    computeAngleDerivatives(p, true);
    Eigen::Matrix<double, 6, 6> H;
    computeHessian(H, moved);
    return H;
  }
};

Eigen::Matrix4f pose_matrix(double x, double y, double z, double roll, double pitch, double yaw) {
  Eigen::Affine3f a = pcl::getTransformation(float(x), float(y), float(z), float(roll), float(pitch), float(yaw));
  return a.matrix();
}
}  // namespace

const char* to_string(Status s) {
  switch (s) {
    case Status::kOk: return "OK";
    case Status::kPoor: return "POOR";
    case Status::kLost: return "LOST";
    case Status::kNotInitialised: return "NOT_INITIALISED";
  }
  return "?";
}

struct Localizer::Impl {
  HessianNdt ndt;
  Cloud::Ptr map{new Cloud};
  Cloud::Ptr plan2d{new Cloud};  // the plan's points at z = 0 (horizontal distance to the plan)
  pcl::KdTreeFLANN<pcl::PointXYZ> kd2d;
  pcl::VoxelGrid<pcl::PointXYZ> grid;
};

Localizer::Localizer(const FloorPlan& plan, const Config& cfg) : impl_(std::make_unique<Impl>()), cfg_(cfg) {
  if (!(cfg.resolution_m > 0) || !(cfg.step_size_m > 0) || !(cfg.epsilon > 0) || cfg.max_iterations < 1 || !(cfg.leaf_m > 0))
    throw std::invalid_argument("ndt: resolution_m, step_size_m, epsilon, max_iterations and leaf_m must be > 0");
  if (!(cfg.outlier_ratio > 0 && cfg.outlier_ratio < 1)) throw std::invalid_argument("ndt: outlier_ratio must be in (0, 1)");
  const auto pts = plan_cloud(plan, cfg.map);
  if (pts.empty()) throw std::invalid_argument("ndt: the plan gives no map points");
  impl_->map->reserve(pts.size());
  for (const auto& p : pts) impl_->map->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  PlanCloudOptions flat = cfg.map;
  flat.z_min_m = 0;
  flat.z_max_m = 1e-3;
  for (const auto& p : plan_cloud(plan, flat))
    if (p.z() == 0.0f) impl_->plan2d->push_back(pcl::PointXYZ(p.x(), p.y(), 0.0f));
  impl_->kd2d.setInputCloud(impl_->plan2d);
  auto& n = impl_->ndt;
  n.setResolution(float(cfg.resolution_m));
  n.setStepSize(cfg.step_size_m);
  n.setTransformationEpsilon(cfg.epsilon);
  n.setMaximumIterations(cfg.max_iterations);
  n.setOulierRatio(cfg.outlier_ratio);
  n.setInputTarget(impl_->map);
  impl_->grid.setLeafSize(float(cfg.leaf_m), float(cfg.leaf_m), float(cfg.leaf_m));
}

Localizer::~Localizer() = default;

size_t Localizer::map_points() const { return impl_->map->size(); }

void Localizer::set_pose(double x, double y, double yaw) {
  x_ = x;
  y_ = y;
  yaw_ = wrap(yaw);
  have_pose_ = true;
  vx_ = vy_ = w_ = 0;
  t_ = 0;
  bad_ = 0;
}

Result Localizer::process(const Scan& s, std::optional<double> dyaw) {
  Result r;
  r.roll = s.roll;
  r.pitch = s.pitch;
  r.z = s.z;
  if (!have_pose_) {
    r.text = "no initial pose";
    return r;
  }
  // 1. Prediction.
  const double dt = (t_ > 0 && s.t > t_) ? s.t - t_ : 0.0;
  const double dpsi = dyaw ? *dyaw : w_ * dt;
  const double ym = yaw_ + 0.5 * dpsi;
  const double px = x_ + (std::cos(ym) * vx_ - std::sin(ym) * vy_) * dt;
  const double py = y_ + (std::sin(ym) * vx_ + std::cos(ym) * vy_) * dt;
  const double pyaw = wrap(yaw_ + dpsi);

  // 2. Downsampling (no de-skew, as hdl_localization: the segmenter already rotates the sweep with the gyro).
  Cloud::Ptr in(new Cloud);
  in->reserve(s.points.size());
  for (const auto& p : s.points)
    if (p.allFinite()) in->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  Cloud::Ptr down(new Cloud);
  impl_->grid.setInputCloud(in);
  impl_->grid.filter(*down);
  r.num_points = int(down->size());

  r.x = px, r.y = py, r.yaw = pyaw;
  bool usable = false;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();
  if (r.num_points >= cfg_.min_points) {
    auto& n = impl_->ndt;
    n.setInputSource(down);
    Cloud aligned;
    n.align(aligned, pose_matrix(px, py, s.z, s.roll, s.pitch, pyaw));
    const Eigen::Matrix4f T = n.getFinalTransformation();
    r.iterations = n.getFinalNumIteration();
    // PCL sets its flag also when the iteration limit ends the search; that is not convergence here.
    r.converged = n.hasConverged() && r.iterations < cfg_.max_iterations;
    r.likelihood = n.getTransformationLikelihood();
    const double nx = T(0, 3), ny = T(1, 3), nyaw = std::atan2(T(1, 0), T(0, 0));
    // Share of points on the plan (horizontal distance), at the pose with the segmenter's gravity part.
    const Eigen::Matrix4f Tout = pose_matrix(nx, ny, s.z, s.roll, s.pitch, nyaw);
    int in_count = 0;
    std::vector<int> idx(1);
    std::vector<float> d2(1);
    const float lim2 = float(cfg_.inlier_distance_m * cfg_.inlier_distance_m);
    for (const auto& q : down->points) {
      const Eigen::Vector4f w = Tout * Eigen::Vector4f(q.x, q.y, q.z, 1.0f);
      if (impl_->kd2d.nearestKSearch(pcl::PointXYZ(w.x(), w.y(), 0.0f), 1, idx, d2) == 1 && d2[0] <= lim2) ++in_count;
    }
    r.inlier_ratio = double(in_count) / double(r.num_points);
    // Covariance: Laplace approximation from the Hessian of the NDT score at the solution.
    Eigen::Matrix<double, 6, 6> H = n.hessian_at(T);
    const int ix[3] = {0, 1, 5};
    Eigen::Matrix3d I3;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) I3(i, j) = -H(ix[i], ix[j]);
    I3 = 0.5 * (I3 + I3.transpose());
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(I3);
    const bool info_ok = I3.allFinite() && es.eigenvalues().minCoeff() > 1e-9;
    if (info_ok) cov = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    const bool finite = std::isfinite(nx) && std::isfinite(ny) && std::isfinite(nyaw);
    usable = finite && r.converged && r.inlier_ratio >= cfg_.min_inlier_ratio && info_ok;
    if (usable) {
      r.x = nx, r.y = ny, r.yaw = wrap(nyaw);
      r.matched = true;
    } else {
      r.text = !finite ? "non-finite NDT result"
               : !r.converged ? "NDT did not converge in " + std::to_string(r.iterations) + " iterations"
               : !info_ok ? "degenerate NDT Hessian"
                          : "too few points on the plan (" + std::to_string(int(100 * r.inlier_ratio)) + " %)";
    }
  } else {
    r.text = "too few points (" + std::to_string(r.num_points) + ")";
  }
  if (!r.matched || !cov.allFinite()) {
    // The prediction: the last covariance grown by the motion (1 m and 0.2 rad per scan without a match).
    cov = Eigen::Vector3d(1.0, 1.0, 0.04).asDiagonal();
  }
  r.covariance = cov;
  const double sigma_xy = std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov.topLeftCorner<2, 2>()).eigenvalues()[1]));
  bad_ = r.matched ? 0 : bad_ + 1;
  if (bad_ >= cfg_.lost_after) r.status = Status::kLost;
  else if (r.matched && r.inlier_ratio >= cfg_.ok_inlier_ratio && sigma_xy <= cfg_.poor_sigma_m) r.status = Status::kOk;
  else {
    r.status = Status::kPoor;
    if (r.text.empty())
      r.text = r.inlier_ratio < cfg_.ok_inlier_ratio ? "few points on the plan" : "large covariance";
  }
  if (r.status == Status::kLost && r.text.empty()) r.text = "no usable match for " + std::to_string(bad_) + " scans";

  // Motion for the next prediction.
  if (dt > 0) {
    const double dx = r.x - x_, dy = r.y - y_;
    const double c = std::cos(yaw_ + 0.5 * wrap(r.yaw - yaw_)), sn = std::sin(yaw_ + 0.5 * wrap(r.yaw - yaw_));
    vx_ = (c * dx + sn * dy) / dt;
    vy_ = (-sn * dx + c * dy) / dt;
    w_ = wrap(r.yaw - yaw_) / dt;
    const double speed = std::hypot(vx_, vy_);
    if (cfg_.max_speed_mps > 0 && speed > cfg_.max_speed_mps) vx_ *= cfg_.max_speed_mps / speed, vy_ *= cfg_.max_speed_mps / speed;
    if (cfg_.max_yaw_rate_rps > 0) w_ = std::clamp(w_, -cfg_.max_yaw_rate_rps, cfg_.max_yaw_rate_rps);
  }
  x_ = r.x, y_ = r.y, yaw_ = r.yaw, t_ = s.t;
  return r;
}

}  // namespace fploc::ndt
