#include "fploc/matcher/matcher.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "fploc/matcher/plan_terms.h"

namespace fploc {

std::unique_ptr<ceres::LossFunction> make_loss(const std::string& name, double scale) {
  if (name == "none" || scale <= 0) return nullptr;
  if (name == "cauchy") return std::make_unique<ceres::CauchyLoss>(scale);
  return std::make_unique<ceres::HuberLoss>(scale);
}

namespace {

// (J^T J)^-1 scaled by sigma^2, with a floor on the eigenvalues (degenerate directions, e.g. along a
// corridor, get a large variance instead of an inverse of zero).
Eigen::Matrix3d covariance_of(ceres::Problem& problem, double sigma2) {
  ceres::Problem::EvaluateOptions eo;
  eo.num_threads = 1;
  ceres::CRSMatrix jac;
  double cost = 0;
  if (!problem.Evaluate(eo, &cost, nullptr, nullptr, &jac) || jac.num_cols != 3) return Eigen::Matrix3d::Identity() * 1e6;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int r = 0; r < jac.num_rows; ++r) {
    Eigen::Vector3d row = Eigen::Vector3d::Zero();
    for (int k = jac.rows[r]; k < jac.rows[r + 1]; ++k) row[jac.cols[k]] = jac.values[k];
    H += row * row.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(H);
  Eigen::Vector3d inv;
  for (int i = 0; i < 3; ++i) inv[i] = 1.0 / std::max(es.eigenvalues()[i], 1e-6);
  return sigma2 * es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

}  // namespace

MatchResult register_frame(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& guess,
                           const MatcherConfig& cfg) {
  MatchResult r;
  r.predicted = guess;
  double x[3] = {guess.x, guess.y, guess.yaw};
  auto loss = make_loss(cfg.loss, cfg.loss_scale_m);
  AssignOptions ao;
  ao.gate_m = std::max(cfg.gate_initial_m, cfg.gate_final_m);
  ao.group_rule = cfg.group_rule;
  ao.stride = std::max(1, cfg.stride);
  if (cfg.max_points > 0 && int(f.points.size()) > cfg.max_points * ao.stride)
    ao.stride = int((f.points.size() + size_t(cfg.max_points) - 1) / size_t(cfg.max_points));
  std::vector<Assignment> as;
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.disable_all_safety_checks = true;
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  so.num_threads = 1;
  so.max_num_iterations = std::max(1, cfg.max_iterations);
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = 1e-8;
  so.parameter_tolerance = 1e-8;
  std::unique_ptr<ceres::Problem> problem;
  bool solved = false;
  // Point targets (kdtree) fix the correspondence for a whole inner solve, like classic ICP, and need
  // many more look-up rounds to converge: give them 6x, so they are measured converged, not truncated.
  const int max_outer = std::max(1, cfg.max_outer) * (lookup.element_targets() ? 1 : 6);
  for (int outer = 0; outer < max_outer; ++outer) {
    assign(lookup, f, Pose2{x[0], x[1], x[2]}, ao, &as);
    if (as.size() < 3) break;
    problem = std::make_unique<ceres::Problem>(po);
    add_frame_term(problem.get(), x, lookup, f, as, cfg.loss, cfg.loss_scale_m);
    const double before[3] = {x[0], x[1], x[2]};
    ceres::Solver::Summary sum;
    ceres::Solve(so, problem.get(), &sum);
    r.iterations += int(sum.iterations.size());
    solved = true;
    const double step = std::hypot(x[0] - before[0], x[1] - before[1]) + std::abs(x[2] - before[2]);
    const bool final_gate = ao.gate_m <= cfg.gate_final_m + 1e-12;
    if (final_gate && step < 1e-5) break;
    ao.gate_m = std::max(cfg.gate_final_m, ao.gate_m * 0.5);
  }
  r.solved = Pose2{x[0], x[1], wrap_angle(x[2])};
  r.pose = r.solved;
  r.fit = evaluate_fit(lookup, f, r.solved, cfg.inlier_m);
  if (solved && problem) r.covariance = covariance_of(*problem, std::max(r.fit.rms_m * r.fit.rms_m, 1e-6));
  else r.covariance = Eigen::Matrix3d::Identity() * 1e6;
  const bool ok = solved && r.fit.num_inliers >= cfg.min_inliers && r.fit.inlier_ratio >= cfg.min_inlier_ratio;
  r.status = ok ? FitStatus::kOk : FitStatus::kPoor;
  if (!solved) r.text = "too few correspondences";
  else if (!ok) r.text = "inliers " + std::to_string(r.fit.num_inliers) + "/" + std::to_string(r.fit.num_points);
  return r;
}

Matcher::Matcher(const NearestLookup& lookup, MatcherConfig cfg) : lookup_(lookup), cfg_(std::move(cfg)) {}

void Matcher::set_pose(const Pose2& p) {
  pose_ = p;
  initialised_ = true;
  have_last_ = false;
  have_velocity_ = false;
  velocity_.setZero();
  poor_count_ = 0;
}

Pose2 Matcher::predict(int64_t utime, std::optional<double> yaw_delta) const {
  Pose2 p = pose_;
  const double dt = (utime - utime_) * 1e-6;
  const bool valid_dt = have_last_ && dt > 0 && dt < 1.0;
  if (cfg_.motion_model && have_velocity_ && valid_dt) {
    p.x += velocity_[0] * dt;
    p.y += velocity_[1] * dt;
    p.yaw += velocity_[2] * dt;
  }
  if (yaw_delta && (valid_dt || !have_last_)) p.yaw = pose_.yaw + *yaw_delta;
  p.yaw = wrap_angle(p.yaw);
  return p;
}

MatchResult Matcher::process(const FeatureFrame& f, std::optional<double> yaw_delta) {
  if (!initialised_) {
    MatchResult r;
    r.status = FitStatus::kNotInitialised;
    r.text = "no initial pose";
    r.fit.num_points = int(f.points.size());
    return r;
  }
  const Pose2 pred = predict(f.utime, yaw_delta);
  MatcherConfig cfg = cfg_;
  const bool lost = poor_count_ >= cfg_.lost_after;
  if (lost) cfg.gate_initial_m *= 2;  // search wider while lost
  // Tracking (the previous frame was registered): the motion model is good to centimetres, so start
  // with the tracking gate (fewer look-up rounds).
  else if (have_last_ && poor_count_ == 0) cfg.gate_initial_m = std::min(cfg.gate_initial_m, cfg.gate_tracking_m);
  MatchResult r = register_frame(lookup_, f, pred, cfg);
  r.predicted = pred;
  const double jump = std::hypot(r.solved.x - pred.x, r.solved.y - pred.y);
  const double jump_yaw = std::abs(wrap_angle(r.solved.yaw - pred.yaw));
  if (r.status == FitStatus::kOk && have_last_ && !lost && (jump > cfg_.max_jump_m || jump_yaw > cfg_.max_jump_rad)) {
    r.status = FitStatus::kPoor;
    r.text = "refused jump of " + std::to_string(jump) + " m";
  }
  const double dt = (f.utime - utime_) * 1e-6;
  if (r.status == FitStatus::kOk) {
    if (have_last_ && dt > 0 && dt < 1.0) {
      velocity_ = Eigen::Vector3d((r.solved.x - pose_.x) / dt, (r.solved.y - pose_.y) / dt,
                                  wrap_angle(r.solved.yaw - pose_.yaw) / dt);
      have_velocity_ = true;
    }
    pose_ = r.solved;
    poor_count_ = 0;
  } else {
    ++poor_count_;
    r.pose = pred;
    pose_ = pred;
    if (poor_count_ >= cfg_.lost_after) {
      r.status = FitStatus::kLost;
      velocity_.setZero();
      have_velocity_ = false;
    }
    if (r.text.empty()) r.text = "poor fit";
  }
  utime_ = f.utime;
  have_last_ = true;
  return r;
}

}  // namespace fploc
