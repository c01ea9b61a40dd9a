#include "fploc/matcher/matcher.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fploc/matcher/plan_terms.h"

namespace fploc::matcher {

namespace {

// sigma^2 H^-1 with a floor on H's eigenvalues (degenerate directions, e.g. along a corridor, get a
// large variance instead of an inverse of zero).
Eigen::Matrix3d covariance_of(const Eigen::Matrix3d& H, double sigma2) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(H);
  Eigen::Vector3d inv;
  for (int i = 0; i < 3; ++i) inv[i] = 1.0 / std::max(es.eigenvalues()[i], 1e-6);
  return sigma2 * es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

struct PriorCost {
  PosePrior p;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    using std::atan2;
    using std::cos;
    using std::sin;
    const T d = x[2] - T(p.pose.yaw);
    r[0] = T(p.sqrt_info[0]) * (x[0] - T(p.pose.x));
    r[1] = T(p.sqrt_info[1]) * (x[1] - T(p.pose.y));
    r[2] = T(p.sqrt_info[2]) * atan2(sin(d), cos(d));
    return true;
  }
};

}  // namespace

MatchResult register_frame(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& guess,
                           const MatcherConfig& cfg, const PosePrior* prior) {
  MatchResult r;
  r.predicted = guess;
  double x[3] = {guess.x, guess.y, guess.yaw};
  AssignOptions ao;
  ao.gate_m = std::max(cfg.max_correspondence_m, cfg.min_correspondence_m);
  ao.group_rule = cfg.group_rule;
  ao.element_weight = cfg.element_weight;
  ao.stride = budget_stride(f.points.size(), cfg.stride, cfg.max_points);
  ao.element_quota = cfg.element_quota;
  // The per-element budget's points, chosen once for the frame at the guess under the final gate (the rounds'
  // poses differ from it by centimetres while tracking; a guess farther off keeps fewer points for sure,
  // every stride-th point as without the budget).
  // Askew faces (askew_max_m) are judged at the guess only while tracking: a prediction good to centimetres.
  if (prior && cfg.askew_max_m > 0) {
    ao.askew_max_m = cfg.askew_max_m;
    ao.askew_point_sigma_m = cfg.as_built.point_sigma_m;
  }
  std::vector<SampledPoint> sel;
  if (selects_per_element(lookup, ao)) {
    AssignOptions so = ao;
    so.gate_m = cfg.min_correspondence_m;
    select_points(lookup, f, guess, so, &sel);
    ao.points = &sel;
  }
  std::vector<Assignment> as, last_as;
  ceres::Problem::Options po;
  po.disable_all_safety_checks = true;
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  so.num_threads = 1;
  so.max_num_iterations = std::max(1, cfg.max_iterations);
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = 1e-8;
  so.parameter_tolerance = 1e-8;
  bool solved = false;
  double last_gate = -1;
  // Point targets (kdtree) fix the correspondence for a whole inner solve, like classic ICP, and need
  // many more look-up rounds to converge: give them 6x, so they are measured converged, not truncated.
  const int max_outer = std::max(1, cfg.max_rounds) * (lookup.element_targets() ? 1 : 6);
  for (int outer = 0; outer < max_outer; ++outer) {
    assign(lookup, f, Pose2{x[0], x[1], x[2]}, ao, &as);
    // The same correspondences under the same gate as the last solve: that solve's result is the answer.
    if (solved && ao.gate_m == last_gate && as == last_as) break;
    if (as.size() < 3) break;
    auto problem = std::make_unique<ceres::Problem>(po);
    add_frame_term(problem.get(), x, lookup, f, as, cfg.loss, cfg.loss_scale_m, 1.0, /*compact=*/true, &cfg.as_built);
    if (prior) problem->AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(new PriorCost{*prior}), nullptr, x);
    const double before[3] = {x[0], x[1], x[2]};
    ceres::Solver::Summary sum;
    ceres::Solve(so, problem.get(), &sum);
    r.iterations += int(sum.iterations.size());
    solved = true;
    last_gate = ao.gate_m;
    std::swap(last_as, as);
    const double step = std::hypot(x[0] - before[0], x[1] - before[1]) + std::abs(x[2] - before[2]);
    const bool final_gate = ao.gate_m <= cfg.min_correspondence_m + 1e-12;
    if (final_gate && step < 1e-5) break;
    ao.gate_m = std::max(cfg.min_correspondence_m, ao.gate_m * 0.5);
  }
  r.solved = Pose2{x[0], x[1], wrap_angle(x[2])};
  r.pose = r.solved;
  // Fit quality over the points the registration used (every ao.stride-th).
  r.fit = evaluate_fit(lookup, f, r.solved, cfg.inlier_m, ao.stride);
  if (solved)  // of the floor-plan terms alone (what this frame says, without the prediction)
    r.covariance = covariance_of(frame_information(lookup, f, last_as, r.solved, cfg.loss, cfg.loss_scale_m),
                                 std::max(r.fit.rms_m * r.fit.rms_m, 1e-6));
  else r.covariance = Eigen::Matrix3d::Identity() * 1e6;
  const bool ok = solved && r.fit.num_inliers >= cfg.min_inliers && r.fit.inlier_ratio >= cfg.min_inlier_ratio;
  r.status = ok ? FitStatus::kOk : FitStatus::kPoor;
  if (!solved) r.text = "too few correspondences";
  else if (!ok) r.text = "inliers " + std::to_string(r.fit.num_inliers) + "/" + std::to_string(r.fit.num_points);
  return r;
}

Matcher::Matcher(const NearestLookup& lookup, MatcherConfig cfg) : lookup_(lookup), cfg_(std::move(cfg)) {}

MatchResult Matcher::search_grid(const FeatureFrame& in, const Pose2& centre, double s_in, double a_in,
                                 const MatcherConfig& cfg, const Eigen::Vector2d* window, double nearest_band) const {
  // One registration converges from about half a metre / a few degrees: starts 2/3 of the half-width apart.
  const double s = s_in * 2 / 3, a = a_in * 2 / 3;
  MatcherConfig c = cfg;
  c.max_correspondence_m = std::max(s, cfg_.min_correspondence_m);
  std::vector<MatchResult> fits;
  fits.reserve(27);
  int iterations = 0;
  for (double dyaw : {0.0, -a, a})
    for (double dx : {0.0, -s, s})
      for (double dy : {0.0, -s, s}) {
        MatchResult ri = register_frame(lookup_, in, Pose2{centre.x + dx, centre.y + dy, wrap_angle(centre.yaw + dyaw)}, c);
        iterations += ri.iterations;
        if (window && ri.status == FitStatus::kOk &&
            (std::hypot(ri.solved.x - centre.x, ri.solved.y - centre.y) > (*window)[0] ||
             std::abs(wrap_angle(ri.solved.yaw - centre.yaw)) > (*window)[1]))
          continue;  // converged out of the window: not a candidate
        fits.push_back(std::move(ri));
      }
  MatchResult r;
  if (fits.empty()) {  // every start converged out of the window
    r = register_frame(lookup_, in, centre, cfg);
    r.status = FitStatus::kPoor;
    r.text = "no fit within the window";
    r.iterations = iterations;
    return r;
  }
  // The fit with the most inliers (then the lower rms), OK ones first. Within an odometry window each fit's
  // inliers are weighted by a prior on its offset from the prediction (the half-widths being 3 sigma):
  // exp(-m^2 / 2 kappa^2) of the Mahalanobis offset m, kappa 1.5, as the grid localizer's correlative search
  // weighs its scores, so that of two places the scan fits about as well the one the odometry supports wins
  // (an office's twin rooms, a room the map covers in part).
  const double sm = std::max(s_in / 3, 1e-3), sa = std::max(a_in / 3, 1e-4);
  auto score = [&](const MatchResult& m) {
    if (!window) return double(m.fit.num_inliers);
    const double dx = (m.solved.x - centre.x) / sm, dy = (m.solved.y - centre.y) / sm;
    const double da = wrap_angle(m.solved.yaw - centre.yaw) / sa;
    return double(m.fit.num_inliers) * std::exp(-(dx * dx + dy * dy + da * da) / (2 * cfg_.search_prior_kappa * cfg_.search_prior_kappa));
  };
  auto better = [&](const MatchResult& x, const MatchResult& y) {
    if ((x.status == FitStatus::kOk) != (y.status == FitStatus::kOk)) return x.status == FitStatus::kOk;
    const double sx = score(x), sy = score(y);
    if (sx != sy) return sx > sy;
    return x.fit.rms_m < y.fit.rms_m;
  };
  size_t best = 0;
  for (size_t i = 1; i < fits.size(); ++i)
    if (better(fits[i], fits[best])) best = i;
  if (!window && nearest_band > 0 && fits[best].status == FitStatus::kOk) {
    // About as good: the nearest to the centre (MatcherConfig::initial_search_band).
    auto offset2 = [&](const MatchResult& m) {
      const double dx = (m.solved.x - centre.x) / sm, dy = (m.solved.y - centre.y) / sm;
      const double da = wrap_angle(m.solved.yaw - centre.yaw) / sa;
      return dx * dx + dy * dy + da * da;
    };
    const double enough = nearest_band * fits[best].fit.num_inliers;
    const size_t top = best;
    for (size_t i = 0; i < fits.size(); ++i)
      if (i != top && fits[i].status == FitStatus::kOk && fits[i].fit.num_inliers >= enough && offset2(fits[i]) < offset2(fits[best]))
        best = i;
  }
  r = std::move(fits[best]);
  r.iterations = iterations;
  return r;
}

void Matcher::set_pose(const Pose2& p, std::optional<double> search_m, std::optional<double> search_yaw) {
  pose_ = p;
  search_m_ = search_m && *search_m > 0 ? *search_m : cfg_.max_correspondence_m;
  search_yaw_ = search_yaw && *search_yaw > 0 ? *search_yaw : cfg_.initial_search_yaw_rad;
  initialised_ = true;
  have_last_ = false;
  have_velocity_ = false;
  twist_ = {};
  poor_count_ = 0;
  dead_reckoned_m_ = dead_reckoned_rad_ = 0;
  gap_window_m_ = gap_window_rad_ = 0;
  refine_armed_ = false;
}

bool Matcher::refine(int64_t utime, const Pose2& p) {
  if (!initialised_ || !have_last_ || utime != last_utime_ || poor_count_ >= cfg_.lost_after) return false;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) return false;
  // Only the position and heading: the velocity stays the matcher's own (taking the optimizer's too was
  // measured worse on the Barcelona pavilion: ATE 42.8 vs 32.6 cm, docs/notes/localization.md).
  const Pose2 q = compose(p, utime_to_tau_);
  // After set_pose the optimizer's window may still hold the track from before the re-initialisation:
  // refined poses are used once one agrees with the matcher's own (within refine_gate_m / _rad), from
  // then on whatever the difference (fed back every frame, it is what the optimizer corrects).
  if (!refine_armed_) {
    if (std::hypot(q.x - pose_.x, q.y - pose_.y) > cfg_.refine_gate_m ||
        std::abs(wrap_angle(q.yaw - pose_.yaw)) > cfg_.refine_gate_rad)
      return false;
    refine_armed_ = true;
  }
  pose_ = {q.x, q.y, wrap_angle(q.yaw)};
  return true;
}

Pose2 Matcher::predict(int64_t tau, std::optional<double> yaw_delta, const std::optional<Pose2>& motion) const {
  if (motion && have_last_) {
    Pose2 p = compose(pose_, *motion);
    p.yaw = wrap_angle(p.yaw);
    return p;
  }
  const double dt = (tau - tau_) * 1e-6;
  if (have_last_ && gap(dt) && dt > cfg_.gap_max_s)  // a velocity that old says nothing; the IMU's yaw change still holds
    return {pose_.x, pose_.y, wrap_angle(yaw_delta ? pose_.yaw + *yaw_delta : pose_.yaw)};
  if (have_last_ && gap(dt)) {
    // Over a gap (MatcherConfig::gap_s): the last body velocity, turned by the IMU's yaw change when given.
    Twist2 v;
    if (cfg_.motion_model && have_velocity_) v = twist_;
    if (yaw_delta) v.w = *yaw_delta / dt;
    Pose2 p = compose(pose_, exp_twist(v, dt));
    p.yaw = wrap_angle(yaw_delta ? pose_.yaw + *yaw_delta : p.yaw);
    return p;
  }
  const bool valid_dt = have_last_ && dt > 0 && dt < 1.0;
  Twist2 v;
  if (cfg_.motion_model && have_velocity_ && valid_dt) v = twist_;
  Pose2 p = valid_dt ? compose(pose_, exp_twist(v, dt)) : pose_;
  if (yaw_delta && (valid_dt || !have_last_)) p.yaw = wrap_angle(pose_.yaw + *yaw_delta);
  return p;
}

MatchResult Matcher::process(const FeatureFrame& f, std::optional<double> yaw_delta, const std::optional<Pose2>& motion) {
  if (!initialised_) {
    MatchResult r;
    r.status = FitStatus::kNotInitialised;
    r.text = "no initial pose";
    r.fit.num_points = int(f.points.size());
    return r;
  }
  const double t_ref = cfg_.deskew ? mean_time(f) : 0.0;
  const int64_t tau = f.utime + std::llround(t_ref * 1e6);
  const Pose2 pred = predict(tau, yaw_delta, motion);
  const bool lost = poor_count_ >= cfg_.lost_after;
  // Gates: tracking (the previous frame OK) starts at the tracking gate, the first frame after set_pose
  // searches within the given pose's uncertainty, after a POOR frame the gate starts wide, and wider
  // still while LOST; each is halved per look-up round down to min_correspondence_m.
  MatcherConfig cfg = cfg_;
  const bool tracking = have_last_ && poor_count_ == 0;
  if (lost) cfg.max_correspondence_m *= 2;
  else if (tracking && !motion) cfg.max_correspondence_m = std::min(cfg.max_correspondence_m, cfg.gate_tracking_m);
  else if (!have_last_) cfg.max_correspondence_m = search_m_;
  // Motion compensation: the sweep's points moved to the sensor frame at utime + t_ref with the motion
  // model's body twist (zero linear velocity until two frames were registered), the IMU's yaw rate.
  Twist2 tw;
  if (cfg_.motion_model && have_velocity_ && !lost) tw = twist_;
  if (std::isfinite(f.sweep_yaw_rate)) tw.w = f.sweep_yaw_rate;
  const bool comp = cfg_.deskew && (tw.vx != 0 || tw.vy != 0 || tw.w != 0);
  if (comp) deskew(f, tw, t_ref, &deskewed_);
  const FeatureFrame& in = comp ? deskewed_ : f;
  MatchResult r;
  // Odometry mode: the window the fit must lie in (the step's sigma, plus what POOR frames accumulated).
  const bool odom_window = motion && have_last_ && cfg_.odom_gate_sigmas > 0;
  double win_m = 0, win_rad = 0;
  if (odom_window) {
    const double step = std::hypot(motion->x, motion->y), turn = std::abs(wrap_angle(motion->yaw));
    const double sm = cfg_.odom_sigma_m + cfg_.odom_sigma_per_m * step;
    const double sa = cfg_.odom_sigma_rad + cfg_.odom_sigma_per_rad * turn + cfg_.odom_sigma_rad_per_m * step;
    win_m = std::min(cfg_.odom_gate_sigmas * (dead_reckoned_m_ + sm), cfg_.odom_max_search_m);
    win_rad = std::min(cfg_.odom_gate_sigmas * (dead_reckoned_rad_ + sa), cfg_.odom_max_search_rad);
    if (tracking) dead_reckoned_m_ = dead_reckoned_rad_ = 0;
    dead_reckoned_m_ += sm;
    dead_reckoned_rad_ += sa;
  }
  // A gap (MatcherConfig::gap_s): its search window, kept over the POOR frames after it until one registers.
  if (!motion && have_last_ && !lost && gap((tau - tau_) * 1e-6)) {
    const double dt = (tau - tau_) * 1e-6;
    gap_dt_s_ = dt;
    gap_window_m_ = std::max(gap_window_m_, std::min(3 * (cfg_.gap_sigma_mps * dt + 0.5 * cfg_.gap_sigma_mps2 * dt * dt), cfg_.gap_max_search_m));
    gap_window_rad_ = std::max(gap_window_rad_, std::min(3 * (yaw_delta ? cfg_.gap_sigma_rad + cfg_.gap_sigma_rad_per_s * dt
                                                                         : cfg_.gap_sigma_rad_per_s_no_imu * dt),
                                                         cfg_.gap_max_search_rad));
  }
  if (lost || motion) gap_window_m_ = gap_window_rad_ = 0;
  const bool gap_search = gap_window_m_ > 2 * cfg_.gate_tracking_m;
  const Eigen::Vector2d window = gap_search ? Eigen::Vector2d(gap_window_m_, gap_window_rad_) : Eigen::Vector2d(win_m, win_rad);
  if (gap_search) {
    // Scans lost for a while: the prediction is known only to within the gap's window.
    r = search_grid(in, pred, gap_window_m_, gap_window_rad_, cfg, &window);
    if (r.status != FitStatus::kOk) {
      char b[160];
      std::snprintf(b, sizeof b, "after a %.1f s gap in the scans: no fit within %.2f m / %.1f deg of the prediction (%s)",
                    gap_dt_s_, gap_window_m_, gap_window_rad_ * 180 / M_PI, r.text.c_str());
      r.text = b;
    }
  } else if (!have_last_ && search_m_ > 2 * cfg_.gate_tracking_m) {
    // First frame from a pose known only to within search_m / search_yaw: one registration converges
    // from about half a metre / a few degrees, so start from a grid over the uncertainty.
    r = search_grid(in, pred, search_m_, search_yaw_, cfg, nullptr, cfg_.initial_search_band);
  } else if (odom_window && !tracking && win_m > 2 * cfg_.gate_tracking_m) {
    // Dead reckoning with the odometry for a while: the prediction is known only to within the window.
    r = search_grid(in, pred, win_m, win_rad, cfg, &window);
  } else {
    PosePrior prior;
    const double dt = (tau - tau_) * 1e-6;
    const bool use_prior = tracking && have_velocity_ && cfg_.motion_model && last_rms_ > 0 && dt > 0 && dt < 1.0 &&
                           cfg_.prediction_sigma_m > 0 && cfg_.prediction_sigma_rad > 0;
    if (motion && tracking && last_rms_ > 0 && cfg_.prediction_sigma_m > 0) {
      // Odometry prediction as the prior: wheel odometry is good to about 10 % of the step (plus 5 cm, 1 deg),
      // which is what holds a frame along a featureless corridor.
      const double step = std::hypot(motion->x, motion->y), sr = std::clamp(last_rms_, 0.005, cfg_.loss_scale_m);
      prior.pose = pred;
      const double sm = 0.05 + 0.1 * step, sa = 0.0175 + 0.1 * std::abs(motion->yaw);
      prior.sqrt_info = Eigen::Vector3d(sr / sm, sr / sm, sr / sa);
    } else if (use_prior) {
      // sigma_r / sigma_pred: the prediction as a measurement among point residuals of rms sigma_r.
      const double grow = std::max(1.0, dt / 0.1), sr = std::clamp(last_rms_, 0.005, cfg_.loss_scale_m);
      prior.pose = pred;
      prior.sqrt_info = Eigen::Vector3d(sr / (cfg_.prediction_sigma_m * grow), sr / (cfg_.prediction_sigma_m * grow),
                                        sr / (cfg_.prediction_sigma_rad * grow));
    }
    const bool odom_prior = motion && tracking && last_rms_ > 0 && cfg_.prediction_sigma_m > 0;
    r = register_frame(lookup_, in, pred, cfg, use_prior || odom_prior ? &prior : nullptr);
  }
  const Pose2 solved_ref = r.solved;
  const double jump = std::hypot(solved_ref.x - pred.x, solved_ref.y - pred.y);
  const double jump_yaw = std::abs(wrap_angle(solved_ref.yaw - pred.yaw));
  if (odom_window || gap_search) {
    // The fit must lie in the window, and one more than 2 sigma from the prediction must explain the scan well.
    const char* whose = gap_search ? "the gap's" : "the odometry's";
    if (r.status == FitStatus::kOk && (jump > window[0] || jump_yaw > window[1])) {
      char b[160];
      std::snprintf(b, sizeof b, "outside %s window: %.2f m / %.1f deg from the prediction (window %.2f m / %.1f deg)", whose,
                    jump, jump_yaw * 180 / M_PI, window[0], window[1] * 180 / M_PI);
      r.status = FitStatus::kPoor;
      r.text = b;
    } else if (r.status == FitStatus::kOk && r.fit.inlier_ratio < cfg_.odom_far_inlier_ratio &&
               std::hypot(jump / std::max(window[0] / 3, 1e-6), jump_yaw / std::max(window[1] / 3, 1e-9)) > 2) {
      char b[200];
      std::snprintf(b, sizeof b, "%.0f %% inliers %.2f m / %.1f deg from the prediction (beyond 2 sigma of %s window: %.0f %% needed)",
                    100 * r.fit.inlier_ratio, jump, jump_yaw * 180 / M_PI, whose, 100 * cfg_.odom_far_inlier_ratio);
      r.status = FitStatus::kPoor;
      r.text = b;
    }
  } else if (r.status == FitStatus::kOk && have_last_ && !lost && (jump > cfg_.max_jump_m || jump_yaw > cfg_.max_jump_rad)) {
    r.status = FitStatus::kPoor;
    r.text = "refused jump of " + std::to_string(jump) + " m";
  }
  const double dt = (tau - tau_) * 1e-6;
  if (r.status == FitStatus::kOk) {
    // The velocity is measured between two registered frames only: after a POOR frame pose_ is the
    // prediction (the twist that made it stays), after LOST it is a stale dead-reckoned pose, and the
    // difference to a re-acquired fit is the correction, not motion (the corridor's renovated world:
    // 1-4 m corrections after LOST read as 20-60 m/s, and the POOR frames after them flew 50 m off the
    // building). Until two frames in a row register, the motion model predicts no motion.
    if (tracking && dt > 0 && dt < 1.0) {
      twist_ = log_twist(pose_, solved_ref, dt);
      // The platform's speed at most: two fixes farther apart than it can drive (a fit that slid along a corridor,
      // or caught a twin of the place) are no motion, and carried as the prediction's velocity through the frames
      // after them they would run the track away along every direction the plan leaves open.
      const double v = std::hypot(twist_.vx, twist_.vy);
      if (cfg_.max_speed_mps > 0 && v > cfg_.max_speed_mps) {
        twist_.vx *= cfg_.max_speed_mps / v;
        twist_.vy *= cfg_.max_speed_mps / v;
      }
      have_velocity_ = true;
    }
    pose_ = solved_ref;
    poor_count_ = 0;
    dead_reckoned_m_ = dead_reckoned_rad_ = 0;
    gap_window_m_ = gap_window_rad_ = 0;
    last_rms_ = r.fit.rms_m;
  } else {
    ++poor_count_;
    pose_ = pred;
    if (poor_count_ >= cfg_.lost_after) {
      r.status = FitStatus::kLost;
      twist_ = {};
      have_velocity_ = false;
    }
    if (r.text.empty()) r.text = "poor fit";
  }
  tau_ = tau;
  have_last_ = true;
  // Back from utime + t_ref to utime with the updated twist (centred on this sweep).
  Twist2 back = have_velocity_ ? twist_ : Twist2{};
  if (std::isfinite(f.sweep_yaw_rate)) back.w = f.sweep_yaw_rate;
  const Pose2 to_utime = exp_twist(back, -t_ref);
  last_utime_ = f.utime;
  utime_to_tau_ = inverse(to_utime);
  r.t_ref = t_ref;
  r.twist = back;
  r.sweep_pose = pose_;
  r.pose = compose(pose_, to_utime);
  r.solved = compose(solved_ref, to_utime);
  r.predicted = compose(pred, to_utime);
  return r;
}

}  // namespace fploc::matcher