// Internal to laser2d: the Ceres refinement of a planar scan's pose on a DistanceField (one residual per
// point, the field at the transformed point with a Huber loss, plus a prior on the pose), its covariance and
// its inlier count. Shared by the grid localizer (scan to map) and the laser odometry (scan to local map).
#pragma once
#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/floorplan/distance_field.h"
#include "fploc/laser2d/grid_localizer.h"

namespace fploc::laser2d::detail {

using FieldGrid = ceres::Grid2D<float, 1>;
using FieldInterp = ceres::BiCubicInterpolator<FieldGrid>;

// A distance field with its bicubic interpolator (the interpolator points into the field's data).
struct InterpolatedField {
  explicit InterpolatedField(std::shared_ptr<const DistanceField> f)
      : df(std::move(f)), grid(df->data().data(), 0, df->height(), 0, df->width()), interp(grid) {}
  std::shared_ptr<const DistanceField> df;
  FieldGrid grid;
  FieldInterp interp;
};

// The prior on a planar pose x = (x, y, yaw): its offsets from p over sxy, sxy and the wrapped yaw over syaw
// (a Ceres auto-diff functor; the field fit and the map refinement add it).
struct PriorCost {
  PriorCost(const Pose2& p, double sxy, double syaw) : p_(p), ixy_(1 / sxy), iyaw_(1 / syaw) {}
  template <class T>
  bool operator()(const T* pose, T* r) const {
    using std::atan2, std::cos, std::sin;
    r[0] = (pose[0] - p_.x) * ixy_;
    r[1] = (pose[1] - p_.y) * ixy_;
    const T d = pose[2] - p_.yaw;
    r[2] = atan2(sin(d), cos(d)) * iyaw_;
    return true;
  }
  Pose2 p_;
  double ixy_, iyaw_;
};

struct FieldFitOptions {
  double point_sigma_m = 0.05, huber_m = 0.05;
  FitLoss loss = FitLoss::kHuber;
  // A redescending loss (Cauchy, Tukey) only pulls from where the points already nearly lie: refine with Huber
  // first (its wider basin), then with `loss` from there (graduated non-convexity, two steps).
  bool huber_first = false;
  int max_iterations = 20;
};

// Refines x = (x, y, yaw) in place from its value, pred with sigmas (sxy, syaw) as the prior; the yaw held when
// fix_yaw. Returns the problem (for the covariance); *cost the final cost, *iterations += the solver's.
std::unique_ptr<ceres::Problem> refine_on_field(const InterpolatedField& f, const FieldFitOptions& o,
                                                const std::vector<Eigen::Vector2d>& pts, const Pose2& pred,
                                                double sxy, double syaw, double* x, double* cost, int* iterations,
                                                bool fix_yaw = false);

// Solves a small pose problem as every laser2d fit does (dense QR, one thread, silent, at most max_iterations).
ceres::Solver::Summary solve_small(ceres::Problem* problem, int max_iterations);

// The inverse of J^T J at the problem's current parameters (loss applied); `fallback` when singular.
Eigen::Matrix3d covariance_of(ceres::Problem& problem, const Eigen::Matrix3d& fallback);

// The points within inlier_m of an occupied cell (nearest-cell distance) at pose x; *sum_sq their squared
// distances.
int count_inliers(const DistanceField& df, const std::vector<Eigen::Vector2d>& pts, const double* x, double inlier_m,
                  double* sum_sq = nullptr);

}  // namespace fploc::laser2d::detail
