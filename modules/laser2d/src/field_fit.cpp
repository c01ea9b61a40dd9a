#include "field_fit.h"

#include <cmath>

namespace fploc::laser2d::detail {

namespace {

// Residual of one point: the distance field at the transformed point [in point_sigma units].
struct PointCost {
  PointCost(const FieldInterp* f, const DistanceField* df, const Eigen::Vector2d& p, double inv_sigma)
      : f_(f), df_(df), p_(p), inv_sigma_(inv_sigma) {}
  template <class T>
  bool operator()(const T* pose, T* r) const {
    const T c = cos(pose[2]), s = sin(pose[2]);
    const T wx = pose[0] + c * p_.x() - s * p_.y();
    const T wy = pose[1] + s * p_.x() + c * p_.y();
    // World -> continuous cell coordinates (cell centre (i, j) at (i, j)).
    const double oc = std::cos(df_->origin_yaw()), os = std::sin(df_->origin_yaw());
    const T dx = wx - df_->origin_x(), dy = wy - df_->origin_y();
    const T ci = (oc * dx + os * dy) / df_->resolution() - 0.5;
    const T cj = (-os * dx + oc * dy) / df_->resolution() - 0.5;
    T d;
    f_->Evaluate(cj, ci, &d);  // Grid2D: row = j, column = i
    r[0] = d * inv_sigma_;
    return true;
  }
  const FieldInterp* f_;
  const DistanceField* df_;
  Eigen::Vector2d p_;
  double inv_sigma_;
};


std::unique_ptr<ceres::Problem> solve(const InterpolatedField& f, const FieldFitOptions& o, FitLoss kind,
                                      const std::vector<Eigen::Vector2d>& pts, const Pose2& pred, double sxy,
                                      double syaw, double* x, double* cost, int* iterations, bool fix_yaw) {
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  auto problem = std::make_unique<ceres::Problem>(po);
  const double inv_sigma = 1 / o.point_sigma_m;
  const double a = o.huber_m * inv_sigma;  // the loss's scale in residual units
  for (const auto& p : pts) {
    ceres::LossFunction* loss = nullptr;
    switch (kind) {
      case FitLoss::kHuber: loss = new ceres::HuberLoss(a); break;
      case FitLoss::kCauchy: loss = new ceres::CauchyLoss(a); break;
      case FitLoss::kTukey: loss = new ceres::TukeyLoss(a); break;
    }
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<PointCost, 1, 3>(new PointCost(&f.interp, f.df.get(), p, inv_sigma)), loss, x);
  }
  problem->AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(new PriorCost(pred, sxy, syaw)), nullptr, x);
  if (fix_yaw) problem->SetManifold(x, new ceres::SubsetManifold(3, {2}));
  const ceres::Solver::Summary sum = solve_small(problem.get(), o.max_iterations);
  if (iterations) *iterations += int(sum.iterations.size());
  *cost = sum.final_cost;
  return problem;
}

}  // namespace

std::unique_ptr<ceres::Problem> refine_on_field(const InterpolatedField& f, const FieldFitOptions& o,
                                                const std::vector<Eigen::Vector2d>& pts, const Pose2& pred,
                                                double sxy, double syaw, double* x, double* cost, int* iterations,
                                                bool fix_yaw) {
  if (o.huber_first && o.loss != FitLoss::kHuber)
    solve(f, o, FitLoss::kHuber, pts, pred, sxy, syaw, x, cost, iterations, fix_yaw);
  return solve(f, o, o.loss, pts, pred, sxy, syaw, x, cost, iterations, fix_yaw);
}

ceres::Solver::Summary solve_small(ceres::Problem* problem, int max_iterations) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary sum;
  ceres::Solve(so, problem, &sum);
  return sum;
}

Eigen::Matrix3d covariance_of(ceres::Problem& problem, const Eigen::Matrix3d& fallback) {
  ceres::CRSMatrix J;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, nullptr, nullptr, &J);
  Eigen::Matrix3d Hm = Eigen::Matrix3d::Zero();
  for (int r = 0; r < J.num_rows; ++r) {
    Eigen::Vector3d row = Eigen::Vector3d::Zero();
    for (int k = J.rows[r]; k < J.rows[r + 1]; ++k) row[J.cols[k]] = J.values[k];
    Hm += row * row.transpose();
  }
  const Eigen::Matrix3d cov = Hm.inverse();
  return cov.allFinite() ? cov : fallback;
}

int count_inliers(const DistanceField& df, const std::vector<Eigen::Vector2d>& pts, const double* x, double inlier_m,
                  double* sum_sq) {
  const double c = std::cos(x[2]), s = std::sin(x[2]);
  int n = 0;
  double ss = 0;
  for (const auto& p : pts) {
    const Eigen::Vector2d w(x[0] + c * p.x() - s * p.y(), x[1] + s * p.x() + c * p.y());
    const double dd = df.nearest(w);
    if (dd < inlier_m) {
      ++n;
      ss += dd * dd;
    }
  }
  if (sum_sq) *sum_sq = ss;
  return n;
}

}  // namespace fploc::laser2d::detail
