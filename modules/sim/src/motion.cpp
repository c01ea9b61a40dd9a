#include "fploc/sim/motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fploc/core/rng.h"

namespace fploc::sim {
namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr int kSamplesPerSeg = 400;
constexpr double kVMin = 0.03;
}  // namespace

Motion::Motion(std::vector<Eigen::Vector2d> control, bool closed, SpeedSpec speed, double target_length, uint64_t seed,
               MotionConfig cfg)
    : ctrl_(std::move(control)), closed_(closed), speed_(speed), cfg_(cfg) {
  if (ctrl_.size() < (closed_ ? 3u : 2u)) throw std::runtime_error("motion: too few control points");
  nseg_ = closed_ ? int(ctrl_.size()) : int(ctrl_.size()) + 1;
  auto build_table = [&] {
    tab_u_.clear();
    tab_s_.clear();
    Eigen::Vector2d prev = spline(0);
    double s = 0;
    const int n = nseg_ * kSamplesPerSeg;
    for (int i = 0; i <= n; ++i) {
      const double u = double(i) / kSamplesPerSeg;
      const Eigen::Vector2d p = spline(u);
      s += (p - prev).norm();
      prev = p;
      tab_u_.push_back(u);
      tab_s_.push_back(s);
    }
    length_ = s;
  };
  build_table();
  if (target_length > 0 && length_ > 0) {
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    for (const auto& p : ctrl_) c += p;
    c /= double(ctrl_.size());
    const double k = target_length / length_;
    for (auto& p : ctrl_) p = c + k * (p - c);
    build_table();
  }
  // Curvature along the path, smoothed over +-0.75 m.
  const int np = std::max(2, int(std::ceil(length_ / ds_prof_)) + 1);
  ds_prof_ = length_ / (np - 1);
  std::vector<double> heading(static_cast<size_t>(np)), kappa(static_cast<size_t>(np), 0.0), w(static_cast<size_t>(np), 0.0);
  for (int j = 0; j < np; ++j) {
    const double s = std::clamp(j * ds_prof_, 0.05, std::max(0.05, length_ - 0.05));
    const Eigen::Vector2d d = spline_d(u_at(s));
    heading[size_t(j)] = std::atan2(d.y(), d.x());
  }
  for (int j = 1; j + 1 < np; ++j)
    kappa[size_t(j)] = std::abs(wrap_angle(heading[size_t(j + 1)] - heading[size_t(j - 1)])) / (2 * ds_prof_);
  const int half = std::max(1, int(0.75 / ds_prof_));
  const double lambda = length_ / std::max(1.0, std::round(length_ / 12.0));
  for (int j = 0; j < np; ++j) {
    double acc = 0;
    int cnt = 0;
    for (int k = j - half; k <= j + half; ++k) {
      int kk = k;
      if (closed_) kk = ((k % (np - 1)) + (np - 1)) % (np - 1);
      else if (k < 0 || k >= np) continue;
      acc += kappa[size_t(kk)];
      ++cnt;
    }
    const double wc = std::min(1.0, (acc / std::max(cnt, 1)) / 0.8);
    // The person pushing the dolly also slows down now and then (every ~12 m, continuous on loops).
    const double wp = 0.5 - 0.5 * std::cos(2 * M_PI * j * ds_prof_ / lambda);
    w[size_t(j)] = 1.0 - (1.0 - wc) * (1.0 - 0.6 * wp);
  }
  const double vmax = speed_.v_max, a = cfg_.accel_mps2;
  double gain = 1.0;  // raised so the profile's maximum is v_max
  auto vprof = [&](int j, double beta) {
    const double s = j * ds_prof_;
    const double ramp = std::min({1.0, std::sqrt(2 * a * s) / vmax, std::sqrt(2 * a * std::max(0.0, length_ - s)) / vmax});
    return std::max(kVMin, std::min(vmax * ramp, gain * vmax * ramp * (1.0 - beta * w[size_t(j)])));
  };
  auto avg_for = [&](double beta) {
    double T = 0;
    for (int j = 0; j + 1 < np; ++j) T += ds_prof_ * 0.5 * (1.0 / vprof(j, beta) + 1.0 / vprof(j + 1, beta));
    return length_ / T;
  };
  double beta = 0;
  for (int outer = 0; outer < 8; ++outer) {
    beta = 0;
    if (avg_for(0) > speed_.v_avg) {
      double lo = 0, hi = 0.97;
      for (int it = 0; it < 50; ++it) {
        const double mid = 0.5 * (lo + hi);
        (avg_for(mid) > speed_.v_avg ? lo : hi) = mid;
      }
      beta = 0.5 * (lo + hi);
    }
    double peak = 0;
    for (int j = 0; j < np; ++j) peak = std::max(peak, vprof(j, beta));
    if (peak >= vmax * 0.999) break;
    gain *= vmax / peak;
  }
  prof_v_.resize(size_t(np));
  for (int j = 0; j < np; ++j) prof_v_[size_t(j)] = vprof(j, beta);
  // Integrate s(t) (RK4).
  time_s_.assign(1, 0.0);
  time_v_.assign(1, speed_at_s(0));
  double s = 0;
  while (s < length_) {
    const double k1 = speed_at_s(s), k2 = speed_at_s(s + 0.5 * dt_ * k1), k3 = speed_at_s(s + 0.5 * dt_ * k2),
                 k4 = speed_at_s(s + dt_ * k3);
    const double sn = s + dt_ / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    if (sn >= length_) {
      t_move_ = (time_s_.size() - 1) * dt_ + dt_ * (length_ - s) / std::max(sn - s, 1e-12);
      s = length_;
      time_s_.push_back(length_);
      time_v_.push_back(speed_at_s(length_));
      break;
    }
    s = sn;
    time_s_.push_back(s);
    time_v_.push_back(speed_at_s(s));
  }
  v_peak_ = *std::max_element(prof_v_.begin(), prof_v_.end());
  // Wobble phases and the tripod's static tilt.
  Rng rng(mix_seed(seed, 0x0B0B));
  for (double& p : ph_) p = rng.uniform(0, 2 * M_PI);
  roll0_ = rng.uniform(-0.4, 0.4);
  pitch0_ = rng.uniform(-0.4, 0.4);
}

Eigen::Vector2d Motion::spline(double u) const {
  u = std::clamp(u, 0.0, double(nseg_));
  int i = std::min(int(std::floor(u)), nseg_ - 1);
  const double t = u - i;
  const int n = int(ctrl_.size());
  auto P = [&](int k) -> const Eigen::Vector2d& {
    if (closed_) return ctrl_[size_t(((k % n) + n) % n)];
    return ctrl_[size_t(std::clamp(k - 2, 0, n - 1))];
  };
  const int b = closed_ ? i - 1 : i;
  const double t2 = t * t, t3 = t2 * t, it = 1 - t;
  return (it * it * it * P(b) + (3 * t3 - 6 * t2 + 4) * P(b + 1) + (-3 * t3 + 3 * t2 + 3 * t + 1) * P(b + 2) +
          t3 * P(b + 3)) /
         6.0;
}

Eigen::Vector2d Motion::spline_d(double u) const {
  u = std::clamp(u, 0.0, double(nseg_));
  int i = std::min(int(std::floor(u)), nseg_ - 1);
  const double t = u - i;
  const int n = int(ctrl_.size());
  auto P = [&](int k) -> const Eigen::Vector2d& {
    if (closed_) return ctrl_[size_t(((k % n) + n) % n)];
    return ctrl_[size_t(std::clamp(k - 2, 0, n - 1))];
  };
  const int b = closed_ ? i - 1 : i;
  const double t2 = t * t, it = 1 - t;
  Eigen::Vector2d d = (-3 * it * it * P(b) + (9 * t2 - 12 * t) * P(b + 1) + (-9 * t2 + 6 * t + 3) * P(b + 2) +
                       3 * t2 * P(b + 3)) /
                      6.0;
  if (d.norm() < 1e-9) {  // the clamped ends of an open path: look slightly inside
    const double u2 = u < nseg_ * 0.5 ? u + 1e-3 : u - 1e-3;
    d = (spline(u2) - spline(u)) * (u2 > u ? 1 : -1);
  }
  return d;
}

double Motion::u_at(double s) const {
  if (s <= 0) return 0;
  if (s >= length_) return double(nseg_);
  const auto it = std::upper_bound(tab_s_.begin(), tab_s_.end(), s);
  const size_t j = size_t(it - tab_s_.begin());
  if (j == 0) return 0;
  if (j >= tab_s_.size()) return double(nseg_);
  const double f = (s - tab_s_[j - 1]) / std::max(tab_s_[j] - tab_s_[j - 1], 1e-15);
  return tab_u_[j - 1] + f * (tab_u_[j] - tab_u_[j - 1]);
}

Eigen::Vector2d Motion::point_at(double s) const { return spline(u_at(s)); }

double Motion::speed_at_s(double s) const {
  if (prof_v_.empty()) return speed_.v_max;
  const double x = std::clamp(s / ds_prof_, 0.0, double(prof_v_.size() - 1));
  const size_t j = std::min(size_t(x), prof_v_.size() - 2);
  const double f = x - double(j);
  return prof_v_[j] * (1 - f) + prof_v_[j + 1] * f;
}

double Motion::s_at_time(double tm, double* v) const {
  if (tm <= 0) {
    if (v) *v = 0;
    return 0;
  }
  if (tm >= t_move_ || time_s_.size() < 2) {
    if (v) *v = 0;
    return length_;
  }
  const double x = tm / dt_;
  const size_t k = std::min(size_t(x), time_s_.size() - 2);
  const double h = dt_, f = x - double(k);
  const double s0 = time_s_[k], s1 = time_s_[k + 1], v0 = time_v_[k], v1 = time_v_[k + 1];
  // Cubic Hermite.
  const double f2 = f * f, f3 = f2 * f;
  const double s = (2 * f3 - 3 * f2 + 1) * s0 + (f3 - 2 * f2 + f) * h * v0 + (-2 * f3 + 3 * f2) * s1 + (f3 - f2) * h * v1;
  if (v) *v = ((6 * f2 - 6 * f) * s0 + (3 * f2 - 4 * f + 1) * h * v0 + (-6 * f2 + 6 * f) * s1 + (3 * f2 - 2 * f) * h * v1) / h;
  return std::clamp(s, 0.0, length_);
}

double Motion::heading_at(double s) const {
  const double u = u_at(s);
  const double us = std::clamp(u, 0.02, nseg_ - 0.02);
  const Eigen::Vector2d d = closed_ ? spline_d(u) : spline_d(us);
  return std::atan2(d.y(), d.x());
}

Eigen::Isometry3d Motion::pose(double t) const {
  t = std::clamp(t, 0.0, duration());
  double v = 0;
  const double s = s_at_time(t - cfg_.preroll_s, &v);
  const double u = u_at(s);
  const Eigen::Vector2d p = spline(u);
  const double heading = heading_at(s);
  const double q = std::clamp(v / std::max(speed_.v_max, 1e-6), 0.0, 1.5);
  const double w = cfg_.wobble_deg * kDeg;
  const double two_pi = 2 * M_PI;
  const double tw = t + cfg_.t0;
  double roll = roll0_ * kDeg + w * q * (0.7 * std::sin(two_pi * 0.8 * tw + ph_[0]) + 0.3 * std::sin(two_pi * 2.1 * tw + ph_[1]));
  double pitch = pitch0_ * kDeg + w * q * (0.7 * std::sin(two_pi * 0.6 * tw + ph_[2]) + 0.3 * std::sin(two_pi * 1.7 * tw + ph_[3]));
  const double yaw = heading + 0.4 * kDeg * q * std::sin(two_pi * 0.35 * tw + ph_[4]);
  // Height changes follow the floor (arc length), so standing still is still.
  double z = cfg_.sensor_height_m + cfg_.height_change_m * std::sin(two_pi * (s + cfg_.s0) / 9.0 + ph_[5]) +
             0.002 * q * std::sin(two_pi * 3.1 * tw + ph_[6]);
  if (cfg_.ground) {
    // Four wheels around the dolly's centre: front/rear along the heading, left/right across it.
    const Eigen::Vector2d f(std::cos(heading), std::sin(heading)), l(-f.y(), f.x());
    const double hl = 0.5 * cfg_.wheelbase_m, ht = 0.5 * cfg_.track_m;
    const double fl = cfg_.ground(s, p + hl * f + ht * l), fr = cfg_.ground(s, p + hl * f - ht * l);
    const double rl = cfg_.ground(s, p - hl * f + ht * l), rr = cfg_.ground(s, p - hl * f - ht * l);
    z += 0.25 * (fl + fr + rl + rr);
    pitch += -std::atan2(0.5 * (fl + fr) - 0.5 * (rl + rr), cfg_.wheelbase_m);  // nose up = negative pitch
    roll += std::atan2(0.5 * (fl + rl) - 0.5 * (fr + rr), cfg_.track_m);        // left side up = positive roll
  }
  return StampedPose::from_rpy(t, Eigen::Vector3d(p.x(), p.y(), z), roll, pitch, yaw).iso();
}

Eigen::Vector3d SensorTrajectory::velocity(double t) const {
  const double h = 1e-3;
  return (pose(t + h).translation() - pose(t - h).translation()) / (2 * h);
}

Eigen::Vector3d SensorTrajectory::acceleration(double t) const {
  const double h = 1e-2;
  return (pose(t + h).translation() - 2 * pose(t).translation() + pose(t - h).translation()) / (h * h);
}

Eigen::Vector3d SensorTrajectory::angular_velocity_body(double t) const {
  const double h = 1e-3;
  const Eigen::Matrix3d dR = pose(t - h).linear().transpose() * pose(t + h).linear();
  const Eigen::AngleAxisd aa(dR);
  return aa.axis() * aa.angle() / (2 * h);
}

std::vector<Eigen::Vector2d> Motion::sample_path(double ds) const {
  std::vector<Eigen::Vector2d> out;
  for (double s = 0; s < length_; s += ds) out.push_back(point_at(s));
  out.push_back(point_at(length_));
  return out;
}

std::vector<ImuSample> simulate_imu(const SensorTrajectory& m, const ImuConfig& cfg, uint64_t seed) {
  Rng rng(mix_seed(seed, 0x1A0));
  Eigen::Vector3d ba, bg;
  for (int i = 0; i < 3; ++i) ba[i] = rng.normal(cfg.accel_bias_sigma);
  for (int i = 0; i < 3; ++i) bg[i] = rng.normal(cfg.gyro_bias_sigma);
  const double dt = 1.0 / cfg.rate_hz;
  const int n = int(std::floor(m.duration() * cfg.rate_hz)) + 1;
  const int sub = std::max(1, cfg.substeps);
  const double h = dt / sub;
  std::vector<ImuSample> out;
  out.reserve(size_t(n));
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    ImuSample s;
    s.t = t;
    // A MEMS IMU's output is band-limited: each sample is the mean over the interval since the previous one
    // (t - dt, t] (an anti-alias filter / delta-angle and delta-velocity output), not a point sample. Gyro: the
    // rotation over the interval divided by dt (exact for any motion). Accelerometer: the mean specific force
    // in the sensor frame, over `substeps` sub-intervals whose acceleration is the velocity change across them
    // (so a short jolt inside the interval is neither missed nor over-weighted).
    const double ta = t - dt;
    const Eigen::Matrix3d dR = m.pose(ta).linear().transpose() * m.pose(t).linear();
    const Eigen::AngleAxisd aa(dR);
    s.gyro = aa.axis() * aa.angle() / dt + bg;
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    for (int j = 0; j < sub; ++j) {
      const double tj = ta + (j + 0.5) * h;
      const Eigen::Vector3d acc = (m.velocity(tj + 0.5 * h) - m.velocity(tj - 0.5 * h)) / h;
      f += m.pose(tj).linear().transpose() * (acc + Eigen::Vector3d(0, 0, kGravity));
    }
    s.accel = f / sub + ba;
    for (int i = 0; i < 3; ++i) s.accel[i] += rng.normal(cfg.accel_noise);
    for (int i = 0; i < 3; ++i) s.gyro[i] += rng.normal(cfg.gyro_noise);
    for (int i = 0; i < 3; ++i) ba[i] += rng.normal(cfg.accel_bias_walk * std::sqrt(dt));
    for (int i = 0; i < 3; ++i) bg[i] += rng.normal(cfg.gyro_bias_walk * std::sqrt(dt));
    out.push_back(s);
  }
  return out;
}

}  // namespace fploc::sim
