#include "fploc/localizer/degeneracy.h"


#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fploc::localizer {

namespace {
Eigen::Matrix3d sym(const Eigen::Matrix3d& P) { return 0.5 * (P + P.transpose()); }
// Positive definite with eigenvalues in [lo, hi].
Eigen::Matrix3d clamp_spd(const Eigen::Matrix3d& P, double lo, double hi) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sym(P));
  const Eigen::Vector3d ev = es.eigenvalues().cwiseMax(lo).cwiseMin(hi);
  return es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
}
}  // namespace

Eigen::Matrix3d tighter_of(const Eigen::Matrix3d& A_in, const Eigen::Matrix3d& B_in) {
  const Eigen::Matrix3d A = clamp_spd(A_in, 1e-14, 1e12), B = clamp_spd(B_in, 1e-14, 1e12);
  Eigen::LLT<Eigen::Matrix3d> llt(A);
  const Eigen::Matrix3d L = llt.matrixL();
  const Eigen::Matrix3d Li = L.inverse();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sym(Li * B * Li.transpose()));
  const Eigen::Vector3d mu = es.eigenvalues().cwiseMin(1.0);
  const Eigen::Matrix3d T = L * es.eigenvectors();
  return sym(T * mu.asDiagonal() * T.transpose());
}

Eigen::Matrix3d add_sigmas(const Eigen::Matrix3d& P_in, const Eigen::Matrix3d& Q_in) {
  const Eigen::Matrix3d P = clamp_spd(P_in, 1e-14, 1e12), Q = clamp_spd(Q_in, 0.0, 1e12);
  Eigen::LLT<Eigen::Matrix3d> llt(P);
  const Eigen::Matrix3d L = llt.matrixL();
  const Eigen::Matrix3d Li = L.inverse();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sym(Li * Q * Li.transpose()));
  const Eigen::Vector3d g = (es.eigenvalues().cwiseMax(0.0).cwiseSqrt().array() + 1.0).square();
  const Eigen::Matrix3d T = L * es.eigenvectors();
  return sym(T * g.asDiagonal() * T.transpose());
}

Eigen::Matrix3d grow_linear(const Eigen::Matrix3d& P, const Eigen::Vector3d& a) {
  return add_sigmas(P, a.cwiseProduct(a).asDiagonal());
}

double weakest_horizontal(const Eigen::Matrix3d& P, double* direction_rad) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(sym(P).topLeftCorner<2, 2>());
  const Eigen::Vector2d v = es.eigenvectors().col(1);  // largest eigenvalue last
  if (direction_rad) {
    double a = std::atan2(v.y(), v.x());
    if (a > M_PI / 2) a -= M_PI;
    if (a <= -M_PI / 2) a += M_PI;
    *direction_rad = a + 0.0;  // no "-0"
  }
  return std::sqrt(std::max(0.0, es.eigenvalues()[1]));
}

double strongest_horizontal(const Eigen::Matrix3d& P) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(sym(P).topLeftCorner<2, 2>(), Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, es.eigenvalues()[0]));
}

Eigen::Vector3d pose_difference(const Pose2& a, const Pose2& b) { return {a.x - b.x, a.y - b.y, wrap_angle(a.yaw - b.yaw)}; }

double mahalanobis2(const Eigen::Vector3d& d, const Eigen::Matrix3d& S) { return d.dot(S.ldlt().solve(d)); }

double chi2_3dof_of_sigmas(double k) {
  // P(chi2_3 <= x) = erf(sqrt(x/2)) - sqrt(2x/pi) exp(-x/2): bisection for the probability erf(k/sqrt2).
  const double p = std::erf(k / std::sqrt(2.0));
  double lo = 0, hi = 200;
  for (int i = 0; i < 100; ++i) {
    const double x = 0.5 * (lo + hi);
    const double c = std::erf(std::sqrt(x / 2)) - std::sqrt(2 * x / M_PI) * std::exp(-x / 2);
    (c < p ? lo : hi) = x;
  }
  return 0.5 * (lo + hi);
}

void UncertaintyTracker::reset(double sigma_m, double sigma_rad) {
  const double v2 = cfg_.max_velocity_error_mps * cfg_.max_velocity_error_mps;
  P_ = Eigen::Vector3d(sigma_m * sigma_m, sigma_m * sigma_m, sigma_rad * sigma_rad).asDiagonal();
  W_ = Eigen::Vector3d(v2, v2, cfg_.yaw_rate_sigma_rps * cfg_.yaw_rate_sigma_rps).asDiagonal();
  have_ = false;
  have_initial_ = true;
  have_mean_ = false;
  confirming_ = false;
  agreeing_ = 0;
  dr_agreeing_ = 0;
  dr_refused_ = false;
  not_ok_since_ok_ = true;  // a re-seeded track: its first fixes are checked against the dead reckoning
}

UncertaintyState UncertaintyTracker::update(int64_t utime, const Eigen::Matrix3d& frame_cov_in, bool frame_valid,
                                            matcher::FitStatus matcher_status, const std::string& matcher_text,
                                            const Pose2* fix, const matcher::Twist2* twist, double inlier_ratio,
                                            const Pose2* motion, double contradicted, const DeadReckoned* dead_reckoned) {
  const double vmax = cfg_.frame.max_variance;
  const double v2 = cfg_.max_velocity_error_mps * cfg_.max_velocity_error_mps;
  const double w2 = cfg_.yaw_rate_sigma_rps * cfg_.yaw_rate_sigma_rps;
  const Eigen::Matrix3d frame_cov = frame_valid ? clamp_spd(frame_cov_in, 1e-14, vmax) : Eigen::Matrix3d::Identity() * vmax;
  bool frame_ok = frame_valid && matcher_status == matcher::FitStatus::kOk;
  const double dt = (utime - last_utime_) * 1e-6;
  const Eigen::Matrix3d unknown_velocity = Eigen::Vector3d(v2, v2, w2).asDiagonal();
  Eigen::Matrix3d P_pred, W_pred;
  const Eigen::Matrix3d P_before = P_;
  if (matcher_status == matcher::FitStatus::kLost) {
    P_pred = Eigen::Matrix3d::Identity() * vmax;
    W_pred = unknown_velocity;
  } else if (!have_ || !(dt >= 0) || (dt > cfg_.max_gap_s && !motion)) {
    // Start (from reset()'s initial uncertainty, if any) or restart after a gap: the frame alone.
    P_pred = have_initial_ && !have_ ? P_ : Eigen::Matrix3d::Identity() * vmax;
    W_pred = have_initial_ && !have_ ? W_ : unknown_velocity;
  } else {
    // The velocity error grows by accel * dt (capped at the platform's speed), the pose's by it * dt.
    const double a = cfg_.accel_sigma_mps2 * dt;
    W_pred = grow_linear(W_, Eigen::Vector3d(a, a, 0.0));
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> ev(sym(W_pred).topLeftCorner<2, 2>());
    W_pred.topLeftCorner<2, 2>() =
        ev.eigenvectors() * ev.eigenvalues().cwiseMin(v2).cwiseMax(0.0).asDiagonal() * ev.eigenvectors().transpose();
    W_pred.block<2, 1>(0, 2).setZero();
    W_pred.block<1, 2>(2, 0).setZero();
    W_pred(2, 2) = std::min(W_pred(2, 2), w2);
    if (motion) {
      // The odometry carries the pose over the step: its own error, not the velocity model's.
      const double step = std::hypot(motion->x, motion->y), turn = std::abs(wrap_angle(motion->yaw));
      const double sxy = cfg_.odom_sigma_m + cfg_.odom_sigma_per_m * step;
      const double syaw = cfg_.odom_sigma_rad + cfg_.odom_sigma_per_rad * turn + cfg_.odom_sigma_rad_per_m * step;
      P_pred = clamp_spd(grow_linear(P_, Eigen::Vector3d(sxy, sxy, syaw)), 1e-14, vmax);
    } else {
      P_pred = clamp_spd(add_sigmas(P_, W_pred * dt * dt), 1e-14, vmax);
    }
  }
  // The tracked prediction: the last fix (or, after a refused one, the last prediction) carried on with
  // the matcher's body twist (its constant velocity and the IMU's yaw rate), or with the odometry's increment,
  // as the matcher predicts.
  const bool continuing = have_ && have_mean_ && dt >= 0 && (dt <= cfg_.max_gap_s || motion) &&
                          matcher_status != matcher::FitStatus::kLost;
  Pose2 mean_pred = mean_;
  if (continuing) mean_pred = motion ? compose(mean_, *motion) : compose(mean_, matcher::exp_twist(twist_, dt));
  mean_pred.yaw = wrap_angle(mean_pred.yaw);
  double innovation_sigma = 0;
  bool refused = false;
  Eigen::Vector3d nu = Eigen::Vector3d::Zero();
  if (fix && continuing && frame_ok && cfg_.gate_sigma > 0) {
    nu = pose_difference(*fix, mean_pred);
    const double d2 = mahalanobis2(nu, sym(P_pred + frame_cov));
    innovation_sigma = std::sqrt(std::max(0.0, d2));
    if (d2 > chi2_3dof_of_sigmas(cfg_.gate_sigma)) {
      refused = true;
      frame_ok = false;  // the prediction goes on; the fix is not taken
    }
  }
  if (fix) {
    if (frame_ok || !continuing) mean_ = Pose2{fix->x, fix->y, wrap_angle(fix->yaw)};
    else mean_ = mean_pred;
    if (twist) twist_ = *twist;
    have_mean_ = matcher_status != matcher::FitStatus::kLost && (continuing || frame_valid);
  }
  if (frame_ok) {
    P_ = tighter_of(P_pred, frame_cov);
    // What the frame observes of the velocity: along the directions it fixes, consecutive fixes give it.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> ef(sym(frame_cov).topLeftCorner<2, 2>());
    Eigen::Vector2d vo;
    for (int i = 0; i < 2; ++i)
      vo[i] = std::sqrt(std::max(0.0, ef.eigenvalues()[i])) < cfg_.poor_sigma_m ? cfg_.velocity_sigma_mps * cfg_.velocity_sigma_mps : v2;
    Eigen::Matrix3d W_obs = Eigen::Matrix3d::Zero();
    W_obs.topLeftCorner<2, 2>() = ef.eigenvectors() * vo.asDiagonal() * ef.eigenvectors().transpose();
    W_obs(2, 2) = w2;
    W_ = tighter_of(W_pred, W_obs);
  } else {
    P_ = P_pred;
    W_ = W_pred;
  }
  have_ = matcher_status != matcher::FitStatus::kLost;
  have_initial_ = false;
  last_utime_ = utime;
  UncertaintyState s;
  s.covariance = P_;
  s.sigma_max_m = weakest_horizontal(P_, &s.weak_direction_rad);
  s.sigma_yaw_rad = std::sqrt(std::max(0.0, P_(2, 2)));
  s.frame_sigma_max_m = weakest_horizontal(frame_cov, nullptr);
  s.frame_degenerate = s.frame_sigma_max_m > cfg_.poor_sigma_m;
  s.status = matcher_status;
  s.text = matcher_text;
  s.innovation_sigma = innovation_sigma;
  s.refused = refused;
  // Re-acquisition (confirm_fixes): a fix accepted where the track was unknown arms it; then accepted fixes in a
  // row are counted.
  // With odometry, what the frames before left (P_ before this step): one odometry step of a metre is itself
  // decimetres uncertain without the position being unknown.
  const double before = strongest_horizontal(motion && continuing ? P_before : P_pred);
  if (frame_ok && !confirming_ && cfg_.confirm_fixes > 0 && before > cfg_.reacquire_sigma_m) {
    confirming_ = true;
    agreeing_ = 0;
  }
  if (confirming_) {
    agreeing_ = frame_ok ? agreeing_ + 1 : 0;
    if (agreeing_ >= cfg_.confirm_fixes) confirming_ = false;
  }
  if (matcher_status == matcher::FitStatus::kOk) {
    char b[200];
    if (refused) {
      std::snprintf(b, sizeof b, "fix refused: %.2f m / %.1f deg from the prediction (Mahalanobis %.1f > %.1f)",
                    std::hypot(nu[0], nu[1]), std::abs(nu[2]) * 180 / M_PI, innovation_sigma, std::sqrt(chi2_3dof_of_sigmas(cfg_.gate_sigma)));
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
    } else if (s.sigma_max_m > cfg_.poor_sigma_m) {
      std::snprintf(b, sizeof b, "position open along %ld deg (1 sigma %.2f m%s)", std::lround(s.weak_direction_rad * 180 / M_PI),
                    s.sigma_max_m, s.frame_degenerate ? ": the plan does not constrain it here" : "");
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
    } else if (s.sigma_yaw_rad > cfg_.poor_sigma_rad) {
      std::snprintf(b, sizeof b, "heading weakly constrained (1 sigma %.1f deg)", s.sigma_yaw_rad * 180 / M_PI);
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
    } else if (confirming_) {
      std::snprintf(b, sizeof b, "re-acquired: %d of %d fixes agreeing", agreeing_, cfg_.confirm_fixes);
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
    } else if (inlier_ratio < cfg_.weak_fit_ratio) {
      std::snprintf(b, sizeof b, "weak fit: %.0f %% of the points on the plan", 100 * inlier_ratio);
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
      s.weak_fit = true;
    } else if (cfg_.max_contradicted > 0 && contradicted > cfg_.max_contradicted) {
      std::snprintf(b, sizeof b, "the map says empty where %.0f %% of the points it knows lie", 100 * contradicted);
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
    }
  }
  // A fix against the dead-reckoned pose (dead_reckoning_gate_sigma), the covariance it would be published with.
  bool held = false;  // published POOR while a stretch with a refused fix counts the fixes that end it
  if (s.status == matcher::FitStatus::kOk && fix && dead_reckoned && cfg_.dead_reckoning_gate_sigma > 0) {
    const Eigen::Vector3d d = pose_difference(*fix, dead_reckoned->pose);
    const double d2 = mahalanobis2(d, sym(s.covariance + clamp_spd(dead_reckoned->covariance, 1e-14, vmax)));
    s.dead_reckoned_sigma = std::sqrt(std::max(0.0, d2));
    ++dr_agreeing_;
    if (d2 > chi2_3dof_of_sigmas(cfg_.dead_reckoning_gate_sigma)) {
      char b[200];
      std::snprintf(b, sizeof b, "%.2f m / %.1f deg from the dead-reckoned pose (1 sigma %.2f m; Mahalanobis %.1f > %.1f)",
                    std::hypot(d[0], d[1]), std::abs(d[2]) * 180 / M_PI, weakest_horizontal(dead_reckoned->covariance, nullptr),
                    s.dead_reckoned_sigma, std::sqrt(chi2_3dof_of_sigmas(cfg_.dead_reckoning_gate_sigma)));
      s.status = matcher::FitStatus::kPoor;
      s.text = b;
      s.off_dead_reckoning = true;
      dr_agreeing_ = 0;
      dr_refused_ = true;
      // Two places the pose may be: the fix's and the dead-reckoned one; the error's second moment.
      s.covariance += d * d.transpose();
      s.sigma_max_m = weakest_horizontal(s.covariance, &s.weak_direction_rad);
      s.sigma_yaw_rad = std::sqrt(std::max(0.0, s.covariance(2, 2)));
    } else if (dr_refused_ && not_ok_since_ok_) {
      // A stretch a fix was refused in (the track slid, or came back on a twin): it ends only with confirm_fixes fixes
      // in a row within the tighter dr_confirm_gate_sigma, each published POOR until then (a fix drifting back at the
      // gate's edge would otherwise end it and be published OK where it was refused a frame before).
      if (d2 > chi2_3dof_of_sigmas(cfg_.dr_confirm_gate_sigma)) dr_agreeing_ = 0;
      if (dr_agreeing_ < std::max(1, cfg_.confirm_fixes)) {
        char b[200];
        std::snprintf(b, sizeof b, "%d of %d fixes within %.0f sigma of the dead-reckoned pose (this one %.2f m, Mahalanobis %.1f)",
                      dr_agreeing_, std::max(1, cfg_.confirm_fixes), cfg_.dr_confirm_gate_sigma, std::hypot(d[0], d[1]),
                      s.dead_reckoned_sigma);
        s.status = matcher::FitStatus::kPoor;
        s.text = b;
        held = true;
      }
    }
  }
  s.confirming = confirming_;
  // The stretch ends with confirm_fixes fixes in a row within the dead reckoning's gate (one slid a little at a time
  // would otherwise re-anchor it on each brief OK), at once without a dead-reckoned pose to check against.
  if (s.status == matcher::FitStatus::kOk) {
    if (!dead_reckoned || dr_agreeing_ >= std::max(1, cfg_.confirm_fixes))
      not_ok_since_ok_ = false, dr_agreeing_ = 0, dr_refused_ = false;
  } else if (held) {
    not_ok_since_ok_ = true;  // still counting
  } else if (matcher_status != matcher::FitStatus::kNotInitialised) {
    not_ok_since_ok_ = true;
    dr_agreeing_ = 0;
  }
  return s;
}

}  // namespace fploc::localizer
