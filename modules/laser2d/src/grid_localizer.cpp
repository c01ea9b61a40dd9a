#include "fploc/laser2d/grid_localizer.h"

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fploc/laser2d/correlative_search.h"

namespace fploc::laser2d {

namespace {

using FieldGrid = ceres::Grid2D<float, 1>;
using FieldInterp = ceres::BiCubicInterpolator<FieldGrid>;

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

struct PriorCost {
  PriorCost(const Pose2& p, double sxy, double syaw) : p_(p), ixy_(1 / sxy), iyaw_(1 / syaw) {}
  template <class T>
  bool operator()(const T* pose, T* r) const {
    r[0] = (pose[0] - p_.x) * ixy_;
    r[1] = (pose[1] - p_.y) * ixy_;
    const T d = pose[2] - p_.yaw;
    r[2] = atan2(sin(d), cos(d)) * iyaw_;
    return true;
  }
  Pose2 p_;
  double ixy_, iyaw_;
};

// Ceres refinement of x (in/out) on the distance field, the prediction as a prior; returns the problem (for the
// covariance) and its final cost.
std::unique_ptr<ceres::Problem> refine_problem(const FieldInterp& interp, const DistanceField& df,
                                               const GridLocalizerConfig& cfg, const std::vector<Eigen::Vector2d>& pts,
                                               const Pose2& pred, double sxy, double syaw, double* x, double* cost,
                                               int* iterations) {
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  auto problem = std::make_unique<ceres::Problem>(po);
  const double inv_sigma = 1 / cfg.point_sigma_m;
  for (const auto& p : pts)
    problem->AddResidualBlock(new ceres::AutoDiffCostFunction<PointCost, 1, 3>(new PointCost(&interp, &df, p, inv_sigma)),
                              new ceres::HuberLoss(cfg.huber_m * inv_sigma), x);
  problem->AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(new PriorCost(pred, sxy, syaw)), nullptr, x);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = cfg.max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary sum;
  ceres::Solve(so, problem.get(), &sum);
  if (iterations) *iterations += int(sum.iterations.size());
  *cost = sum.final_cost;
  return problem;
}

}  // namespace

struct GridLocalizer::Impl {
  std::unique_ptr<ceres::Problem> refine_at(const std::vector<Eigen::Vector2d>& pts, const Pose2& pred, double sxy,
                                            double syaw, double* x, double* cost, int* iterations) const {
    return refine_problem(interp, *df, cfg, pts, pred, sxy, syaw, x, cost, iterations);
  }
  std::shared_ptr<const DistanceField> df;
  FieldGrid grid;
  FieldInterp interp;
  std::unique_ptr<ScorePyramid> pyramid;  // exp(-d^2 / 2 s^2) per cell and its max-pooled levels
  GridLocalizerConfig cfg;
  Pose2 pose;
  double sxy = 0, syaw = 0;  // current uncertainty of `pose`
  std::optional<Pose2> last_odom;
  int poor_run = 0;
  bool first = true;

  Impl(std::shared_ptr<const DistanceField> f, const GridLocalizerConfig& c)
      : df(std::move(f)), grid(df->data().data(), 0, df->height(), 0, df->width()), interp(grid) {
    pyramid = std::make_unique<ScorePyramid>(*df, c.score_sigma_m, c.search_levels);
    cfg = c;
  }
};

GridLocalizer::GridLocalizer(std::shared_ptr<const DistanceField> field, GridLocalizerConfig cfg) : cfg_(cfg) {
  if (!field || field->width() <= 0) throw std::invalid_argument("grid localizer: empty distance field");
  impl_ = std::make_unique<Impl>(std::move(field), cfg_);
}

GridLocalizer::~GridLocalizer() = default;

void GridLocalizer::set_initial_pose(const Pose2& pose) {
  impl_->pose = pose;
  impl_->sxy = cfg_.initial_sigma_xy_m;
  impl_->syaw = cfg_.initial_sigma_yaw_rad;
  impl_->last_odom.reset();
  impl_->poor_run = 0;
  impl_->first = true;
  have_pose_ = true;
}

std::vector<Eigen::Vector2d> scan_points(const std::vector<float>& ranges, double angle_min, double increment,
                                         double min_range, double max_range, const Pose2& mount) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(ranges.size());
  const double c = std::cos(mount.yaw), s = std::sin(mount.yaw);
  for (size_t i = 0; i < ranges.size(); ++i) {
    const double r = ranges[i];
    if (!std::isfinite(r) || r < min_range || r >= max_range) continue;
    const double a = angle_min + double(i) * increment;
    const double lx = r * std::cos(a), ly = r * std::sin(a);
    out.emplace_back(mount.x + c * lx - s * ly, mount.y + s * lx + c * ly);
  }
  return out;
}

GridResult GridLocalizer::update(const std::vector<Eigen::Vector2d>& points_in, const std::optional<Pose2>& odom) {
  GridResult res;
  if (!have_pose_) return res;
  Impl& m = *impl_;
  const DistanceField& df = *m.df;

  // 1. Prediction and its uncertainty.
  Pose2 pred = m.pose;
  double sxy = m.sxy, syaw = m.syaw;
  if (odom && m.last_odom) {
    const Pose2 inc = between(*m.last_odom, *odom);
    const double step = std::hypot(inc.x, inc.y), turn = std::abs(wrap_angle(inc.yaw));
    pred = compose(m.pose, inc);
    const double qxy = cfg_.sigma_xy_m + cfg_.sigma_xy_per_m * step;
    const double qyaw = cfg_.sigma_yaw_rad + cfg_.sigma_yaw_per_rad * turn + cfg_.sigma_yaw_per_m * step;
    sxy = std::sqrt(sxy * sxy + qxy * qxy + step * step * syaw * syaw);
    syaw = std::sqrt(syaw * syaw + qyaw * qyaw);
  } else if (!m.first) {
    sxy = std::sqrt(sxy * sxy + cfg_.no_odom_sigma_xy_m * cfg_.no_odom_sigma_xy_m);
    syaw = std::sqrt(syaw * syaw + cfg_.no_odom_sigma_yaw_rad * cfg_.no_odom_sigma_yaw_rad);
  }
  m.first = false;
  if (odom) m.last_odom = odom;

  // Points: every k-th so that at most max_points remain.
  std::vector<Eigen::Vector2d> pts;
  {
    const size_t n = points_in.size();
    const size_t k = cfg_.max_points > 0 ? std::max<size_t>(1, (n + size_t(cfg_.max_points) - 1) / size_t(cfg_.max_points)) : 1;
    for (size_t i = 0; i < n; i += k) {
      const double r = points_in[i].norm();
      if (r >= cfg_.min_range_m && r <= cfg_.max_range_m) pts.push_back(points_in[i]);
    }
  }
  res.num_points = int(pts.size());
  const double wxy = std::clamp(cfg_.window_sigmas * sxy, 2 * df.resolution(), cfg_.max_window_xy_m);
  const double wyaw = std::clamp(cfg_.window_sigmas * syaw, cfg_.search_yaw_step_rad, cfg_.max_window_yaw_rad);
  res.search_xy_m = wxy;
  res.search_yaw_rad = wyaw;
  if (pts.size() < 10) {
    m.pose = pred;
    m.sxy = sxy;
    m.syaw = syaw;
    ++m.poor_run;
    res.pose = pred;
    res.status = m.poor_run >= cfg_.lost_after ? GridStatus::kLost : GridStatus::kPoor;
    return res;
  }

  // 2. Correlative search around the prediction (branch and bound; the best `refine_candidates` distinct
  // candidates within candidate_ratio of the best are kept).
  const size_t sk = std::max<size_t>(1, pts.size() / 100);
  std::vector<Eigen::Vector2d> sp;
  for (size_t i = 0; i < pts.size(); i += sk) sp.push_back(pts[i]);
  SearchWindow win;
  win.center = pred;
  win.xy_m = wxy;
  win.yaw_rad = wyaw;
  win.yaw_step_rad = cfg_.search_yaw_step_rad;
  win.sigma_xy_m = sxy;
  win.sigma_yaw_rad = syaw;
  win.prior_kappa = cfg_.prior_weight_sigmas;
  SearchOptions sopt;
  sopt.keep = std::max(1, cfg_.refine_candidates);
  sopt.min_ratio = cfg_.candidate_ratio;
  SearchStats sst;
  const std::vector<SearchCandidate> cands = correlative_search(df, *m.pyramid, sp, win, sopt, &sst);
  res.candidates = int(sst.leaves);
  res.score = cands.empty() ? 0 : cands.front().score;

  // 3. Refinement of each candidate on the distance field with the prediction as a prior; the one of least
  // cost (robust point residuals + prior) is the fit (a corridor's shifted candidate scores almost as well in
  // the search, but its refined cost is higher).
  std::unique_ptr<ceres::Problem> problem;
  std::vector<std::array<double, 3>> xs;  // parameter blocks (alive while their problem is)
  xs.reserve(cands.size() + 1);
  for (const auto& c : cands) xs.push_back({c.pose.x, c.pose.y, c.pose.yaw});
  if (xs.empty()) xs.push_back({pred.x, pred.y, pred.yaw});
  size_t bi = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < xs.size(); ++i) {
    double cost = 0;
    auto pb = m.refine_at(pts, pred, sxy, syaw, xs[i].data(), &cost, &res.iterations);
    if (cost < best_cost) {
      best_cost = cost;
      problem = std::move(pb);
      bi = i;
    }
  }
  const double* x = xs[bi].data();
  res.refined = int(xs.size());

  // 4. Status from the inliers at the refined pose.
  const Pose2 est{x[0], x[1], wrap_angle(x[2])};
  double ss = 0;
  int inl = 0;
  {
    const double c = std::cos(est.yaw), s = std::sin(est.yaw);
    for (const auto& p : pts) {
      const Eigen::Vector2d w(est.x + c * p.x() - s * p.y(), est.y + s * p.x() + c * p.y());
      const double d = df.nearest(w);
      if (d < cfg_.inlier_m) {
        ++inl;
        ss += d * d;
      }
    }
  }
  res.num_inliers = inl;
  res.inlier_ratio = double(inl) / double(pts.size());
  res.rms_m = inl > 0 ? std::sqrt(ss / inl) : 0;
  const double ex = est.x - pred.x, ey = est.y - pred.y, eyaw = wrap_angle(est.yaw - pred.yaw);
  const double m2 = (ex * ex + ey * ey) / (sxy * sxy) + eyaw * eyaw / (syaw * syaw);
  const bool near = m2 <= cfg_.gate_sigmas * cfg_.gate_sigmas;
  // The refinement may not leave the window searched (a scan of one flat wall fits anywhere along it).
  const bool inside = std::hypot(ex, ey) <= wxy + df.resolution() && std::abs(eyaw) <= wyaw + cfg_.search_yaw_step_rad;
  if (inside && res.inlier_ratio >= cfg_.min_inlier_ratio || (near && res.inlier_ratio >= cfg_.min_inlier_ratio_near)) {
    // Covariance from the Jacobian at the solution (loss applied).
    ceres::CRSMatrix J;
    problem->Evaluate(ceres::Problem::EvaluateOptions(), nullptr, nullptr, nullptr, &J);
    Eigen::Matrix3d Hm = Eigen::Matrix3d::Zero();
    for (int r = 0; r < J.num_rows; ++r) {
      Eigen::Vector3d row = Eigen::Vector3d::Zero();
      for (int k = J.rows[r]; k < J.rows[r + 1]; ++k) row[J.cols[k]] = J.values[k];
      Hm += row * row.transpose();
    }
    res.covariance = Hm.inverse();
    if (!res.covariance.allFinite()) res.covariance = Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
    m.pose = est;
    m.sxy = std::sqrt(std::max(res.covariance(0, 0), res.covariance(1, 1)));
    m.syaw = std::sqrt(res.covariance(2, 2));
    m.poor_run = 0;
    res.status = GridStatus::kOk;
    res.pose = est;
  } else {
    m.pose = pred;
    m.sxy = sxy;
    m.syaw = syaw;
    ++m.poor_run;
    res.status = m.poor_run >= cfg_.lost_after ? GridStatus::kLost : GridStatus::kPoor;
    res.pose = pred;
    res.covariance = Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
  }
  return res;
}

}  // namespace fploc::laser2d
