#include "fploc/odometry/odometry.h"

#include <Eigen/Dense>
#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>

namespace fploc::odometry {

struct Odometry2D::Map {
  std::vector<Eigen::Vector2d> pts;
  std::vector<Eigen::Vector2d> normals;
  std::vector<char> valid;
  struct Cloud {
    const std::vector<Eigen::Vector2d>* p;
    size_t kdtree_get_point_count() const { return p->size(); }
    double kdtree_get_pt(size_t i, size_t d) const { return (*p)[i][int(d)]; }
    template <class B>
    bool kdtree_get_bbox(B&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2, uint32_t>;
  Cloud cloud{&pts};
  std::unique_ptr<Tree> tree;

  void rebuild(const std::deque<std::vector<Eigen::Vector2d>>& kfs, double static_support_m) {
    pts.clear();
    std::vector<int> key;  // each point's keyframe
    for (size_t k = 0; k < kfs.size(); ++k) {
      pts.insert(pts.end(), kfs[k].begin(), kfs[k].end());
      key.insert(key.end(), kfs[k].size(), int(k));
    }
    tree = std::make_unique<Tree>(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree->buildIndex();
    normals.assign(pts.size(), Eigen::Vector2d::Zero());
    valid.assign(pts.size(), 0);
    const bool static_only = static_support_m > 0 && kfs.size() >= 2;
    // Normals from a fixed radius (a k-nearest neighbourhood collapses onto a noisy clump once several
    // keyframes overlap).
    std::vector<std::pair<uint32_t, double>> found;
    size_t kept = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      found.clear();
      const size_t n = tree->radiusSearch(pts[i].data(), 0.25 * 0.25, found, nanoflann::SearchParams(32, 0.0f, false));
      if (n < 4) continue;
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (size_t j = 0; j < n; ++j) mean += pts[found[j].first];
      mean /= double(n);
      Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
      for (size_t j = 0; j < n; ++j) C += (pts[found[j].first] - mean) * (pts[found[j].first] - mean).transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
      if (es.eigenvalues()[0] > 0.05 * es.eigenvalues()[1]) continue;  // not a line locally
      normals[i] = es.eigenvectors().col(0);
      if (static_only) {
        // Seen again: a point of another keyframe on this point's line.
        bool seen = false;
        for (size_t j = 0; j < n && !seen; ++j)
          seen = key[found[j].first] != key[i] && std::abs(normals[i].dot(pts[found[j].first] - pts[i])) <= static_support_m;
        if (!seen) continue;
      }
      valid[i] = 1;
      ++kept;
    }
    if (!static_only) return;
    // Only the static points are searched (a point's nearest neighbour must not be a person's trail that hides the
    // wall behind it).
    size_t w = 0;
    for (size_t i = 0; i < pts.size(); ++i)
      if (valid[i]) pts[w] = pts[i], normals[w] = normals[i], ++w;
    pts.resize(kept);
    normals.resize(kept);
    valid.assign(kept, 1);
    tree = std::make_unique<Tree>(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree->buildIndex();
  }
};

Odometry2D::Odometry2D(OdometryConfig cfg) : cfg_(cfg), map_(std::make_unique<Map>()) {}
Odometry2D::~Odometry2D() = default;

size_t Odometry2D::map_points() const { return map_->pts.size(); }

void Odometry2D::set_pose(const Pose2& p) {
  pose_ = p;
  have_pose_ = true;
  have_last_ = have_velocity_ = false;
  keyframes_.clear();
  map_->pts.clear();
  map_->tree.reset();
}

void Odometry2D::set_pose(const Pose2& p, const Eigen::Vector3d& velocity) {
  set_pose(p);
  velocity_ = velocity;
  have_velocity_ = true;
}

const FeatureFrame& Odometry2D::subsampled(const FeatureFrame& f_in) {
  if (!(cfg_.max_points > 0 && f_in.points.size() > size_t(cfg_.max_points))) return f_in;
  const size_t stride = (f_in.points.size() + size_t(cfg_.max_points) - 1) / size_t(cfg_.max_points);
  sub_.utime = f_in.utime;
  sub_.points.clear();
  for (size_t i = 0; i < f_in.points.size(); i += stride) sub_.points.push_back(f_in.points[i]);
  return sub_;
}

void Odometry2D::add_keyframe(const FeatureFrame& f, const Pose2& p) {
  std::vector<Eigen::Vector2d> w;
  w.reserve(f.points.size());
  for (const auto& fp : f.points) w.push_back(matcher::transform(p, fp.p));
  keyframes_.push_back(std::move(w));
  while (int(keyframes_.size()) > std::max(1, cfg_.map_keyframes)) keyframes_.pop_front();
  map_->rebuild(keyframes_, cfg_.static_support_m);
  last_key_ = p;
}

OdometryResult Odometry2D::process(const FeatureFrame& f_in) {
  const FeatureFrame& f = subsampled(f_in);
  OdometryResult r;
  r.num_points = int(f.points.size());
  if (!have_pose_) return r;
  if (keyframes_.empty()) {  // first frame: it is the map
    add_keyframe(f, pose_);
    utime_ = f.utime;
    have_last_ = true;
    r.pose = pose_;
    r.ok = true;
    r.keyframe = true;
    r.num_inliers = r.num_points;
    return r;
  }
  const double dt = (f.utime - utime_) * 1e-6;
  Pose2 x = pose_;
  if (have_velocity_ && dt > 0 && dt < 1.0) {
    x.x += velocity_[0] * dt;
    x.y += velocity_[1] * dt;
    x.yaw += velocity_[2] * dt;
  }
  const bool yaw_measured = have_yaw_change_ && dt > 0 && dt < 1.0;
  if (yaw_measured) x.yaw = pose_.yaw + yaw_change_;
  have_yaw_change_ = false;
  const Pose2 pred = x;
  // The prediction as a prior (OdometryConfig::prediction_sigma_m), in the points' units.
  Eigen::Vector3d prior = Eigen::Vector3d::Zero();
  if (have_velocity_ && cfg_.prediction_sigma_m > 0 && cfg_.prediction_sigma_rad > 0) {
    const double wxy = std::pow(cfg_.point_sigma_m / cfg_.prediction_sigma_m, 2);
    prior = Eigen::Vector3d(wxy, wxy, std::pow(cfg_.point_sigma_m / cfg_.prediction_sigma_rad, 2));
  }
  // A measured yaw change (set_yaw_change) holds the yaw with its own sigma.
  if (yaw_measured) prior[2] = std::pow(cfg_.point_sigma_m / yaw_change_sigma_, 2);
  const double gate2 = cfg_.max_correspondence_m * cfg_.max_correspondence_m;
  int inliers = 0;
  double sum2 = 0;
  for (int it = 0; it < cfg_.max_iterations; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero(), Hin = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    const double c = std::cos(x.yaw), s = std::sin(x.yaw);
    inliers = 0;
    sum2 = 0;
    for (const auto& fp : f.points) {
      const Eigen::Vector2d pw = matcher::transform(x, fp.p);
      uint32_t idx;
      double d2;
      if (map_->pts.empty() || map_->tree->knnSearch(pw.data(), 1, &idx, &d2) < 1 || d2 > gate2 || !map_->valid[idx]) continue;
      const Eigen::Vector2d& n = map_->normals[idx];
      const double e = n.dot(pw - map_->pts[idx]);
      const Eigen::Vector3d J(n.x(), n.y(), n.dot(Eigen::Vector2d(-s * fp.p.x() - c * fp.p.y(), c * fp.p.x() - s * fp.p.y())));
      const double w = std::abs(e) <= cfg_.huber_m ? 1.0 : cfg_.huber_m / std::abs(e);
      H += w * J * J.transpose();
      g += w * J * e;
      if (std::abs(e) <= cfg_.huber_m) Hin += J * J.transpose();
      if (std::abs(e) <= 2 * cfg_.huber_m) {
        ++inliers;
        sum2 += e * e;
      }
    }
    r.iterations = it + 1;
    r.information = Hin / (cfg_.point_sigma_m * cfg_.point_sigma_m);
    if (inliers < 10) break;
    const Eigen::Vector3d off(x.x - pred.x, x.y - pred.y, wrap_angle(x.yaw - pred.yaw));
    H += prior.asDiagonal();
    g += prior.cwiseProduct(off);
    const Eigen::Vector3d dx = -(H + 1e-6 * Eigen::Matrix3d::Identity()).ldlt().solve(g);
    x.x += dx[0];
    x.y += dx[1];
    x.yaw += dx[2];
    if (dx.head<2>().norm() < 1e-5 && std::abs(dx[2]) < 1e-6) break;
  }
  x.yaw = wrap_angle(x.yaw);
  r.num_inliers = inliers;
  r.rms_m = inliers > 0 ? std::sqrt(sum2 / inliers) : 0;
  r.ok = inliers >= 10 && double(inliers) >= cfg_.min_inlier_ratio * double(std::max(1, r.num_points));
  if (!r.ok) {
    r.information.setZero();
    x = pred;
    have_velocity_ = false;  // hold the pose instead of extrapolating into nowhere
  }
  if (r.ok && dt > 0 && dt < 1.0) {
    velocity_ = Eigen::Vector3d((x.x - pose_.x) / dt, (x.y - pose_.y) / dt, wrap_angle(x.yaw - pose_.yaw) / dt);
    have_velocity_ = true;
  }
  pose_ = x;
  utime_ = f.utime;
  r.pose = x;
  if (r.ok && (std::hypot(x.x - last_key_.x, x.y - last_key_.y) >= cfg_.keyframe_distance_m ||
               std::abs(wrap_angle(x.yaw - last_key_.yaw)) >= cfg_.keyframe_angle_rad)) {
    add_keyframe(f, x);
    r.keyframe = true;
  }
  return r;
}

}  // namespace fploc::odometry