#include "fploc/segmentation/gravity_fusion.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "segmenter_constants.h"

namespace fploc::seg {

namespace {
std::string fmt_deg(const char* f, double a, double b = 0) {
  char buf[200];
  std::snprintf(buf, sizeof buf, f, a / k::kDeg, b / k::kDeg);
  return buf;
}
double angle_of(const Eigen::Vector3d& tilt) { return std::asin(std::min(1.0, tilt.norm())); }
}  // namespace

const char* to_string(GravityFusion::Mode m) { return m == GravityFusion::Mode::kLevel ? "level" : "slope"; }

void GravityFusion::add_gyro(const Eigen::Vector3d& w, int64_t utime) {
  if (!w.allFinite() || w.norm() > k::kMaxGyroRate || utime <= 0) return;
  if (!gyro_.empty() && utime <= gyro_.back().first) {
    if (utime < gyro_.back().first - k::kGyroKeepUs) {  // time went back: a new log/sensor
      gyro_.clear();
      started_ = false;
    } else {
      return;  // duplicate or out of order
    }
  }
  gyro_.emplace_back(utime, w);
  while (gyro_.size() > 2 && gyro_.front().first < utime - 2 * k::kGyroKeepUs) gyro_.pop_front();
}

bool GravityFusion::rotation(int64_t ta, int64_t tb, const Eigen::Vector3d& bias, Eigen::Matrix3d* R) const {
  *R = Eigen::Matrix3d::Identity();
  if (gyro_.size() < 2) return false;
  const int64_t lo = std::min(ta, tb), hi = std::max(ta, tb);
  if (gyro_.front().first > lo + k::kGyroEdgeUs || gyro_.back().first < hi - k::kGyroEdgeUs) return false;
  int64_t prev = gyro_.front().first;
  for (const auto& g : gyro_) {  // no gap longer than kGyroMaxGapUs inside [lo, hi]
    if (g.first > hi + k::kGyroMaxGapUs) break;
    if (g.first >= lo - k::kGyroMaxGapUs && g.first - prev > k::kGyroMaxGapUs) return false;
    prev = g.first;
  }
  // Each gyro sample is the mean rate over the interval since the previous sample (an IMU's band-limited output,
  // as the OS-1's and the simulator's): the rotation is the sum of rate x overlap of [lo, hi] with each sample's
  // interval (exact for a rate constant per interval; a short jolt inside an interval is neither lost nor
  // over-weighted as with point samples interpolated). The first sample's interval: the next spacing.
  auto it = std::lower_bound(gyro_.begin(), gyro_.end(), lo,
                             [](const std::pair<int64_t, Eigen::Vector3d>& s, int64_t v) { return s.first < v; });
  std::vector<Eigen::Vector3d> steps;
  for (; it != gyro_.end(); ++it) {
    const int64_t end = it->first;
    const int64_t start = it == gyro_.begin() ? std::min(lo, end - ((it + 1) != gyro_.end() ? (it + 1)->first - end : 0))
                                               : (it - 1)->first;
    const int64_t a = std::max(lo, start), b = std::min(hi, end);
    if (b > a) steps.push_back((it->second - bias) * (1e-6 * double(b - a)));
    if (end >= hi) break;
  }
  if (it == gyro_.end() && gyro_.back().first < hi)  // beyond the last sample: its rate held
    steps.push_back((gyro_.back().second - bias) * (1e-6 * double(hi - std::max(lo, gyro_.back().first))));
  auto apply = [&](const Eigen::Vector3d& th) {
    const double ang = th.norm();
    if (ang > 0) *R = *R * Eigen::AngleAxisd(ang, th / ang).toRotationMatrix();
  };
  // Orientation at tb relative to ta: forward in time for tb > ta, the inverse (backward) otherwise.
  if (tb >= ta) {
    for (const auto& th : steps) apply(th);
  } else {
    for (auto r = steps.rbegin(); r != steps.rend(); ++r) apply(-*r);
  }
  return true;
}

GravityFusion::Result& GravityFusion::take_planes(const Eigen::Vector3d& up, double plane_sigma, Result& r) {
  g_ = up;
  sigma_ = plane_sigma;
  r.valid = r.from_planes = true;
  r.up = up;
  r.sigma = plane_sigma;
  return r;
}

GravityFusion::Result& GravityFusion::settle_to_planes(const Eigen::Vector3d& g_pred, const Eigen::Vector3d& up,
                                                      double plane_sigma, double dt, Result& r) {
  const double kp = 1 - std::exp(-std::max(0.0, dt) / cfg_.slope_plane_tau_s);
  g_ = (g_pred + kp * (up - g_pred)).normalized();
  sigma_ = std::hypot(plane_sigma, angle_of(up - g_));
  r.valid = true;
  r.up = g_;
  r.sigma = sigma_;
  r.settling = true;
  return r;
}

double GravityFusion::sigma_after(double dt) const {
  return std::min(M_PI, sigma_ + cfg_.gyro_bias_sigma * dt + cfg_.gyro_noise * std::sqrt(std::max(0.0, dt) * 0.01));
}

void GravityFusion::carry_by_gyro(const Eigen::Vector3d& g_pred, double dt, Result& r) {
  g_ = g_pred;
  sigma_ = sigma_after(dt);
  r.valid = r.predicted = true;
  r.up = g_;
  r.sigma = sigma_;
}

double GravityFusion::slope_deg() const { return mode_ == Mode::kSlope ? angle_of(o_) / k::kDeg : 0.0; }

GravityFusion::Result GravityFusion::update(int64_t t, const Eigen::Vector3d* plane_up, double plane_sigma,
                                            const Eigen::Vector3d* accel, const Eigen::Vector3d& bias,
                                            bool plane_repeated) {
  Result r;
  const bool acc_ok = accel && accel->allFinite() && std::abs(accel->norm() - k::kGravityMs2) < cfg_.accel_norm_tol;
  // The accelerometer's direction, less its tilt bias (learned on level floors; sensor-fixed, like the bias).
  const Eigen::Vector3d ad_raw = acc_ok ? Eigen::Vector3d(accel->normalized()) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d ad = acc_ok ? Eigen::Vector3d((ad_raw - acc_bias_).normalized()) : ad_raw;
  if (!started_) {
    if (!plane_up) return r;  // nothing to carry yet
    started_ = true;
    t_ = t;
    settle_until_ = 0;
    mode_ = Mode::kLevel;
    o_.setZero();
    u_.setZero();
    if (acc_ok) acc_lp_ = ad, have_acc_lp_ = true;
    return take_planes(*plane_up, plane_sigma, r);
  }
  const double dt = 1e-6 * double(t - t_);
  Eigen::Matrix3d R;
  const bool gyro_ok = dt >= 0 && dt <= 1.0 && rotation(t_, t, bias, &R);
  // The gyro live but late for this scan (late_gyro_hold_s): without planes nothing is carried yet, and level
  // planes that turned are held off, both without an update, until the gyro covers the interval.
  const bool late = !gyro_ok && dt > 0 && dt < cfg_.late_gyro_hold_s && !gyro_.empty() &&
                    gyro_.back().first >= t_ - k::kGyroMaxGapUs;
  if (late && !plane_up) return r;
  if (late && mode_ == Mode::kLevel) {
    Eigen::Vector3d nu = *plane_up - g_;
    nu -= nu.dot(*plane_up) * *plane_up;
    if (angle_of(nu) > cfg_.change_deg * k::kDeg) {
      r.valid = r.held = true;
      r.up = g_;
      r.sigma = sigma_after(dt);
      r.text = fmt_deg("the gyro has not reached this scan (IMU late) and the planes are %.2f deg off the last gravity: "
                       "that gravity held, the planes not taken", angle_of(nu));
      return r;  // nothing updated: the next scan's gyro covers this interval too
    }
  }
  if (!gyro_ok) R.setIdentity();
  t_ = t;
  const Eigen::Matrix3d Rt = R.transpose();
  // Carry the world-fixed vectors into this scan's sensor frame.
  const Eigen::Vector3d g_pred = (Rt * g_).normalized();
  const Eigen::Vector3d o_pred = Rt * o_;
  u_ = std::exp(-std::max(0.0, dt) / cfg_.change_leak_s) * (Rt * u_);
  // Standing still: for at least still_s the gyro quiet and the specific force unchanged (its direction within
  // still_accel_dir of where the stretch began, carried by the gyro; its length within still_accel_norm of the
  // last scan's). Then the accelerometer measures gravity alone: its tilt bias is learned fast. (A platform
  // moving at a steady speed or acceleration for a second without rotating or vibrating would pass: not a dolly.)
  bool still = false;
  double w_max = M_PI;
  if (gyro_ok) {
    w_max = 0;
    for (auto it = gyro_.rbegin(); it != gyro_.rend() && it->first > t - int64_t(dt * 1e6); ++it)
      w_max = std::max(w_max, (it->second - bias).norm());
  }
  // The gyro quiet over the interval: the sensor did not turn (planes that moved are another surface or a bad
  // fit, e.g. inside a closed lift car).
  const bool gyro_quiet = gyro_ok && w_max < cfg_.still_rate;
  if (acc_ok && gyro_ok && have_prev_acc_) {
    still_ref_ = (Rt * still_ref_).normalized();
    const bool quiet = w_max < cfg_.still_rate && std::abs(accel->norm() - prev_acc_norm_) < cfg_.still_accel_norm;
    if (quiet && still_run_ > 0 && (ad_raw - still_ref_).norm() < cfg_.still_accel_dir) {
      still_run_ += dt;
    } else if (quiet) {
      still_run_ = 1e-9;  // a stretch begins here
      still_ref_ = ad_raw;
      still_sum_.setZero();
      still_n_ = 0;
    } else {
      still_run_ = 0;
    }
    still = still_run_ >= cfg_.still_s;
  } else {
    still_run_ = 0;
  }
  have_prev_acc_ = acc_ok;
  if (acc_ok) prev_acc_norm_ = accel->norm();
  if (have_acc_lp_) acc_lp_ = (Rt * acc_lp_).normalized();
  if (acc_ok) {
    if (!have_acc_lp_) acc_lp_ = ad, have_acc_lp_ = true;
    else acc_lp_ = (acc_lp_ + (1 - std::exp(-std::max(0.0, dt) / cfg_.accel_lp_tau_s)) * (ad - acc_lp_)).normalized();
  }

  if (plane_up && plane_repeated && mode_ == Mode::kSlope && gyro_ok) {
    // Last scan's planes again, in last scan's axes: on a slope the plane step the gyro did not see would be
    // taken for another surface (the tilt moved by the sensor's pitch over one scan). Carried by the gyro.
    plane_up = nullptr;
    if (!r.text.empty()) r.text += "; ";
    r.text += "planes are last scan's (the fit kept its start): attitude carried by the gyro";
  }
  if (!plane_up) {
    if (!gyro_ok) return r;  // no source: the caller holds with a grown sigma
    o_ = o_pred;  // (world-fixed, in this scan's axes)
    carry_by_gyro(g_pred, dt, r);
    return r;
  }
  const Eigen::Vector3d& p = *plane_up;
  bool stepped = false;  // slope: the planes stepped to another surface in this scan

  if (mode_ == Mode::kLevel) {
    if (gyro_ok) {
      // The planes' change the gyro does not explain (g is last scan's gravity carried: the planes' when they
      // were taken).
      Eigen::Vector3d nu = p - g_pred;
      nu -= nu.dot(p) * p;
      if (nu.norm() < std::sin(15 * k::kDeg)) u_ += held_ > 0 ? Eigen::Vector3d(nu - held_nu_) : nu;
      held_nu_ = nu;
      u_ -= u_.dot(p) * p;
      const double change = std::max(angle_of(u_), angle_of(nu));
      if (change > cfg_.change_deg * k::kDeg) {
        const Eigen::Vector3d o_gyro = angle_of(nu) > angle_of(u_) ? Eigen::Vector3d(-nu) : Eigen::Vector3d(-u_);
        bool agree = false;
        double acc_off = M_PI;
        if (have_acc_lp_) {
          Eigen::Vector3d o_acc = acc_lp_ - p;
          acc_off = (o_acc - o_gyro).norm();
          agree = acc_off < std::max(std::sin(cfg_.accel_agree_deg * k::kDeg), 0.5 * o_gyro.norm());
        }
        if (agree) {
          mode_ = Mode::kSlope;
          o_ = o_gyro;
          o_sigma_ = std::max(0.05 * k::kDeg, 0.02 * angle_of(o_));
          u_.setZero();
          refused_ = false;
          held_ = 0;
          r.text = fmt_deg("planes turned %.2f deg more than the gyro (the accelerometer agrees within %.2f deg): on a slope",
                           change, std::asin(std::min(1.0, acc_off)));
        } else if (!refused_) {
          refused_ = true;
          r.text = fmt_deg("planes turned %.2f deg more than the gyro, the accelerometer disagrees by %.2f deg: taken as level",
                           change, std::asin(std::min(1.0, acc_off)));
        }
      } else if (change < 0.5 * cfg_.change_deg * k::kDeg) {
        refused_ = false;
      }
      if (mode_ == Mode::kLevel && nu.norm() > std::sin(cfg_.step_deg * k::kDeg) &&
          (held_ < cfg_.max_hold_scans || (held_ > 0 && gyro_quiet)) && !refused_) {
        // One scan's planes off what the gyro carried (a compromise plane, another surface seen for a moment):
        // gravity carried by the gyro for a while; the planes again once they agree (or after max_hold_scans).
        if (held_ == 0) {
          r.text = fmt_deg("planes %.2f deg off the gyro's prediction: attitude carried by the gyro", angle_of(nu));
        } else if (held_ == cfg_.max_hold_scans) {
          r.text = fmt_deg("planes %.2f deg off the gyro, which is quiet (not turning): still carried by the gyro", angle_of(nu));
        }
        ++held_;
        // Standing still the accelerometer measures gravity alone (its tilt bias calibrated): it keeps the
        // gyro's bias from drifting a long hold.
        Eigen::Vector3d gp = g_pred;
        if (still && still_s_ > 0) gp = (gp + (1 - std::exp(-std::max(0.0, dt) / cfg_.accel_lp_tau_s)) * (ad - gp)).normalized();
        carry_by_gyro(gp, dt, r);
        return r;
      }
      if (held_ > 0 && mode_ == Mode::kLevel)
        r.text = fmt_deg(held_ >= cfg_.max_hold_scans ? "planes %.2f deg off the gyro for too long: the planes again"
                                                      : "planes agree with the gyro again (%.2f deg)", angle_of(nu));
      held_ = 0;
    }
    if (mode_ == Mode::kLevel) {
      const double turn_rate = gyro_ok && dt > 0 ? std::abs(Eigen::AngleAxisd(R).angle() * Eigen::AngleAxisd(R).axis().dot(p)) / dt : 0.0;
      if (acc_ok && held_ == 0 && (still || turn_rate < cfg_.accel_bias_max_turn_rate)) {
        // Level floor: the planes are gravity; what the accelerometer says beside it is its bias. Standing
        // still it measures gravity alone (the mean over the still stretch); moving, the platform's
        // accelerations average out over accel_bias_tau_s (not while turning: the centripetal acceleration of a
        // path turning mostly one way does not), 10x slower once a standstill has calibrated it.
        Eigen::Vector3d d = ad_raw - p;
        if (still_run_ > 0) still_sum_ += d, ++still_n_;
        if (still) {
          // The mean over the whole still stretch (its first scans included), sensor-fixed like the bias.
          if (still_s_ == 0) r.text = fmt_deg("standing still: the accelerometer's tilt bias calibrated (%.2f deg)",
                                              angle_of(still_sum_ / std::max(1, still_n_)));
          still_s_ += dt;
          acc_bias_ = still_sum_ / std::max(1, still_n_);
        } else {
          const double tau = (still_s_ > 0 ? 10 : 1) * cfg_.accel_bias_tau_s;
          const double kb = 1 - std::exp(-std::max(0.0, dt) / tau);
          acc_bias_ += kb * (d - acc_bias_);
        }
      }
      if (gyro_ok && t < settle_until_ && cfg_.slope_plane_tau_s > 0) return settle_to_planes(g_pred, p, plane_sigma, dt, r);
      return take_planes(p, plane_sigma, r);
    }
  } else if (gyro_ok) {
    Eigen::Vector3d nu = p - (g_pred - o_pred);
    nu -= nu.dot(p) * p;
    if (nu.norm() > std::sin(cfg_.step_deg * k::kDeg) && nu.norm() < std::sin(cfg_.change_deg * k::kDeg) &&
        held_ < cfg_.max_hold_scans) {
      // The planes stepped by less than another surface's change (change_deg; the fit moving between the ramp
      // and the floor or landing is a clean step of the slope, ground_kink.cpp), the sensor did not: one scan's
      // fit off the surface (a compromise over the ramp and the landing beyond, a few returns). Taken as another
      // surface only when the planes stay off for max_hold_scans scans: a step taken from one scan's fit stays
      // in the tilt when the planes come back by less than step_deg (0.3 deg of attitude error for seconds).
      // Meanwhile gravity and the tilt are carried by the gyro (world-fixed: the sensor's own rotation only).
      if (held_ == 0)
        r.text = fmt_deg("plane step of %.2f deg the gyro did not see: attitude carried by the gyro until it persists",
                         angle_of(nu));
      ++held_;
      o_ = o_pred;
      carry_by_gyro(g_pred, dt, r);
      return r;
    }
    if (nu.norm() > std::sin(cfg_.step_deg * k::kDeg)) {
      // The planes stepped and stayed: the fit is on another surface. Gravity carried by the gyro.
      stepped = true;
      o_ = g_pred - p;
      o_sigma_ += 0.02 * nu.norm();
      r.text = fmt_deg("plane step of %.2f deg the gyro did not see: another surface, its slope %.2f deg", angle_of(nu),
                       angle_of(o_));
    } else {
      if (held_ > 0) r.text = fmt_deg("planes on the surface followed again (%.2f deg): the step was one fit's", angle_of(nu));
      o_ = o_pred;  // the same surfaces: the planes carry the sensor's rotation
    }
    held_ = 0;
  }
  if (acc_ok) {
    // The accelerometer's gravity, slowly: the platform's accelerations average out. Across the slope (the
    // tilt's component perpendicular to the slope's direction) faster while the sensor does not turn: a
    // platform driving up or down a slope accelerates along it, and without turning there is no centripetal
    // acceleration across it, so there the accelerometer (its tilt bias removed) measures gravity alone up
    // to its noise.
    const double kacc = 1 - std::exp(-std::max(0.0, dt) / cfg_.accel_tau_s);
    Eigen::Vector3d e = (ad - p) - o_;
    e -= e.dot(p) * p;
    const double turn_rate =
        gyro_ok && dt > 0 ? std::abs(Eigen::AngleAxisd(R).angle() * Eigen::AngleAxisd(R).axis().dot(p)) / dt : M_PI;
    if (turn_rate < cfg_.accel_bias_max_turn_rate && angle_of(o_) > cfg_.level_deg * k::kDeg) {
      const Eigen::Vector3d along = o_.normalized();
      const Eigen::Vector3d e_along = e.dot(along) * along;
      const double kcross = 1 - std::exp(-std::max(0.0, dt) / k::kCrossSlopeAccelTauS);
      o_ += kacc * e_along + kcross * (e - e_along);
    } else {
      o_ += kacc * e;
    }
    o_sigma_ = std::max(0.05 * k::kDeg, o_sigma_ * (1 - 0.5 * kacc));
  }
  o_ -= o_.dot(p) * p;
  // The accelerometer's gravity (low-passed ~1 s, bias-corrected) on the planes' up: the surfaces are level again
  // (the fit left the ramp for the level floor past its head, a few tenths of a degree the gyro did not carry).
  Eigen::Vector3d acc_off = have_acc_lp_ ? Eigen::Vector3d(acc_lp_ - p) : Eigen::Vector3d::Constant(1.0);
  acc_off -= acc_off.dot(p) * p;
  const bool acc_level = have_acc_lp_ && still_s_ > 0 && angle_of(o_) < cfg_.level_by_accel_deg * k::kDeg &&
                         angle_of(acc_off) < 0.5 * cfg_.level_deg * k::kDeg;
  if (angle_of(o_) < cfg_.level_deg * k::kDeg || acc_level) {
    r.text += std::string(r.text.empty() ? "" : "; ") +
              (acc_level ? fmt_deg("surface tilt %.2f deg but the accelerometer agrees with the planes within %.2f deg: level again, "
                                   "attitude from the planes", angle_of(o_), angle_of(acc_off))
                         : fmt_deg("surface tilt %.2f deg: level again, attitude from the planes", angle_of(o_)));
    mode_ = Mode::kLevel;
    o_.setZero();
    u_.setZero();
    held_ = 0;
    if (stepped && gyro_ok && cfg_.level_settle_s > 0 && cfg_.slope_plane_tau_s > 0) {
      settle_until_ = t + std::llround(1e6 * cfg_.level_settle_s);
      return settle_to_planes(g_pred, p, plane_sigma, dt, r);
    }
    return take_planes(p, plane_sigma, r);
  }
  g_ = (p + o_).normalized();
  if (gyro_ok && cfg_.slope_plane_tau_s > 0) {
    // On a slope the planes are a measurement of gravity (through the tilt), the gyro's carry the prediction: a
    // first-order blend, so one scan's plane fit does not pass into the attitude as it is.
    const double kp = 1 - std::exp(-std::max(0.0, dt) / cfg_.slope_plane_tau_s);
    g_ = (g_pred + kp * (g_ - g_pred)).normalized();
  }
  sigma_ = std::hypot(plane_sigma, o_sigma_);
  r.valid = true;
  r.up = g_;
  r.sigma = sigma_;
  return r;
}

}  // namespace fploc::seg
