#include "fploc/segmentation/segmenter.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <numeric>

namespace fploc::seg {

namespace {
constexpr double kDeg = M_PI / 180.0;

bool same_beams(const BeamIntrinsics& a, const BeamIntrinsics& b) {
  return a.altitude_deg == b.altitude_deg && a.azimuth_deg == b.azimuth_deg &&
         a.beam_offset_mm == b.beam_offset_mm && a.lidar_to_sensor == b.lidar_to_sensor;
}

// Orthonormal basis (e1, e2) of the plane orthogonal to `u`.
void basis(const Eigen::Vector3d& u, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const Eigen::Vector3d a = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (a - a.dot(u) * u).normalized();
  e2 = u.cross(e1);
}

// Weighted least-squares plane through accumulated moments; normal oriented against `up`.
struct Moments {
  double w = 0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
  void add(const Eigen::Vector3d& p, double wi) {
    w += wi;
    s += wi * p;
    ss.noalias() += wi * p * p.transpose();
  }
  bool plane(const Eigen::Vector3d& ref, const Eigen::Vector3d& up, Eigen::Vector4d& out,
             Eigen::Vector3d* eigenvalues = nullptr) const {
    if (w <= 0) return false;
    const Eigen::Vector3d c = s / w;
    const Eigen::Matrix3d cov = ss / w - c * c.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(cov);
    Eigen::Vector3d n = es.eigenvectors().col(0);
    if (!n.allFinite()) return false;
    if (n.dot(up) > 0) n = -n;
    const Eigen::Vector3d cw = c + ref;
    out << n, -n.dot(cw);
    if (eigenvalues) *eigenvalues = es.eigenvalues() * w;
    return true;
  }
};

// max(0, q) without a branch (std::max compiled to one here and mispredicted at every band edge); same
// value as std::max(0.f, q) for every q, NaN included (maxss returns its second operand then).
inline float max0(float q) {
#if defined(__SSE__)
  return _mm_cvtss_f32(_mm_max_ss(_mm_set_ss(q), _mm_setzero_ps()));
#else
  return std::max(0.f, q);
#endif
}

double median_inplace(std::vector<float>& v) {
  if (v.empty()) return 0.0;
  auto mid = v.begin() + v.size() / 2;
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}
}  // namespace

const char* to_string(SegStatus s) {
  switch (s) {
    case SegStatus::kOk: return "OK";
    case SegStatus::kNoCeiling: return "NO_CEILING";
    case SegStatus::kBadInput: return "BAD_INPUT";
    case SegStatus::kEmpty: return "EMPTY";
  }
  return "?";
}

Eigen::Vector3d up_from_roll_pitch(double roll, double pitch) {
  // up_sensor = R^T e_z with R = Rz(yaw) Ry(pitch) Rx(roll).
  return {-std::sin(pitch), std::sin(roll) * std::cos(pitch), std::cos(roll) * std::cos(pitch)};
}

void roll_pitch_from_up(const Eigen::Vector3d& u, double& roll, double& pitch) {
  roll = std::atan2(u.y(), u.z());
  pitch = std::atan2(-u.x(), std::hypot(u.y(), u.z()));
}

Segmenter::Segmenter(SegmenterConfig cfg) : cfg_(cfg) {}
Segmenter::~Segmenter() = default;

void Segmenter::add_accel(const Eigen::Vector3d& a) {
  if (!a.allFinite() || a.norm() < 1.0) return;
  accel_sum_ += a;
  ++accel_n_;
}

void Segmenter::add_gyro(const Eigen::Vector3d& w, int64_t utime) {
  if (!w.allFinite() || w.norm() > 35.0 || utime <= 0) return;  // > 2000 deg/s: not a rate an OS-1 IMU reports
  if (!gyro_.empty() && utime <= gyro_.back().first) {
    if (utime < gyro_.back().first - 1000000) gyro_.clear();  // time went back (> 1 s): a new log/sensor
    else return;                                               // duplicate or out of order: ignore
  }
  gyro_.emplace_back(utime, w);
  while (gyro_.size() > 2 && gyro_.front().first < utime - 1000000) gyro_.pop_front();  // keep ~1 s
}

Eigen::Vector3d Segmenter::gyro_at(int64_t t) const {
  // Linear interpolation between samples; the nearest sample outside their span; minus the estimated bias.
  if (t <= gyro_.front().first) return gyro_.front().second - gyro_bias_;
  if (t >= gyro_.back().first) return gyro_.back().second - gyro_bias_;
  auto it = std::lower_bound(gyro_.begin(), gyro_.end(), t,
                             [](const std::pair<int64_t, Eigen::Vector3d>& s, int64_t v) { return s.first < v; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double f = double(t - a.first) / double(std::max<int64_t>(1, b.first - a.first));
  return (1 - f) * a.second + f * b.second - gyro_bias_;
}

bool Segmenter::gyro_covers(int64_t ta, int64_t tb) const {
  // Samples from before ta to after tb (within 20 ms) without a gap longer than 50 ms.
  if (gyro_.size() < 2 || gyro_.front().first > ta + 20000 || gyro_.back().first < tb - 20000) return false;
  int64_t prev = gyro_.front().first;
  for (const auto& g : gyro_) {
    if (g.first > tb + 50000) break;
    if (g.first >= ta - 50000 && g.first - prev > 50000) return false;
    prev = g.first;
  }
  return true;
}

Eigen::Matrix3d Segmenter::gyro_rotation(int64_t ta, int64_t tb) const {
  // Orientation at tb relative to ta (body frame), midpoint rule in steps of at most 5 ms.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  const int steps = int(std::max<int64_t>(1, (std::abs(tb - ta) + 4999) / 5000));
  for (int k = 0; k < steps; ++k) {
    const int64_t a = ta + (tb - ta) * k / steps, b = ta + (tb - ta) * (k + 1) / steps;
    const Eigen::Vector3d th = gyro_at(a + (b - a) / 2) * (1e-6 * double(b - a));
    const double ang = th.norm();
    if (ang > 0) R = R * Eigen::AngleAxisd(ang, th / ang).toRotationMatrix();
  }
  return R;
}

void Segmenter::update_gyro_bias(const Eigen::Vector3d& up) {
  // Gyro bias (the part perpendicular to gravity, the one that tilts the de-skew) from consecutive
  // ceilings: the up vector of the previous frame carried to this mid-sweep by the (bias-corrected) gyro
  // should be this frame's up; a residual rotation rate delta = (u_pred x u) / dt is bias left over.
  // Low-pass (a few seconds); steps of more than 0.03 rad/s (a wrong plane) are ignored.
  const int64_t t = sweep_tm_;
  if (t == 0 || !cfg_.deskew_gyro) {
    have_bias_ref_ = false;
    return;
  }
  if (have_bias_ref_ && t > bias_ref_t_ && t - bias_ref_t_ <= 600000 && gyro_covers(bias_ref_t_, t)) {
    const double dt = 1e-6 * double(t - bias_ref_t_);
    const Eigen::Vector3d u_pred = gyro_rotation(bias_ref_t_, t).transpose() * bias_ref_up_;
    const Eigen::Vector3d delta = u_pred.cross(up) / dt;
    if (delta.norm() < 0.03) gyro_bias_ += 0.05 * delta;
  }
  have_bias_ref_ = true;
  bias_ref_t_ = t;
  bias_ref_up_ = up;
}

bool Segmenter::deskew_rotations(const Scan& scan) {
  // Orientation at each column time relative to mid-sweep, R_mid<-c = prod exp([w dt]x), integrated
  // column by column (midpoint rate, linearly interpolated gyro). Needs gyro samples covering the sweep
  // (within 20 ms of both ends) and increasing column times.
  const int W = scan.width;
  sweep_tm_ = 0;
  if (!cfg_.deskew_gyro || gyro_.size() < 2 || int(scan.column_utime.size()) != W) return false;
  const bool cvalid = int(scan.column_valid.size()) == W;
  int c0 = -1, c1 = -1;
  for (int c = 0; c < W; ++c) {
    if (scan.column_utime[c] == 0 || (cvalid && !scan.column_valid[c])) continue;
    if (c1 >= 0 && scan.column_utime[c] < scan.column_utime[c1]) return false;  // not in time order
    if (c0 < 0) c0 = c;
    c1 = c;
  }
  if (c0 < 0 || c1 <= c0) return false;
  const int64_t t0 = scan.column_utime[c0], t1 = scan.column_utime[c1];
  if (t1 - t0 > 500000) return false;  // a sweep longer than 0.5 s: times do not make sense
  if (gyro_.front().first > t0 + 20000 || gyro_.back().first < t1 - 20000) return false;
  // Column times (invalid columns take the previous column's time: they carry no returns anyway).
  col_t_.resize(W);
  int64_t last = t0;
  for (int c = 0; c < W; ++c) {
    if (c >= c0 && c <= c1 && scan.column_utime[c] != 0 && !(cvalid && !scan.column_valid[c])) last = scan.column_utime[c];
    col_t_[c] = last;
  }
  const int64_t tm = t0 + (t1 - t0) / 2;
  sweep_tm_ = tm;  // the gyro covers this sweep (planes refer to mid-sweep)
  // Largest rotation over half a sweep: skip the work when it is below 0.001 deg.
  double peak = 0;
  for (const auto& g : gyro_)
    if (g.first >= t0 - 20000 && g.first <= t1 + 20000) peak = std::max(peak, g.second.norm());
  if (peak * 0.5e-6 * double(t1 - t0) < 2e-5) return false;
  col_rot_.resize(W);
  int cm = c0;
  while (cm < c1 && col_t_[cm] < tm) ++cm;
  auto step = [&](const Eigen::Matrix3d& R, int64_t ta, int64_t tb) {
    const Eigen::Vector3d th = gyro_at(ta + (tb - ta) / 2) * (1e-6 * double(tb - ta));
    const double a = th.norm();
    return a > 0 ? Eigen::Matrix3d(R * Eigen::AngleAxisd(a, th / a).toRotationMatrix()) : R;
  };
  const Eigen::Matrix3d Rm = step(Eigen::Matrix3d::Identity(), tm, col_t_[cm]);
  Eigen::Matrix3d R = Rm;
  col_rot_[cm] = R.cast<float>();
  for (int c = cm + 1; c < W; ++c) {
    R = step(R, col_t_[c - 1], col_t_[c]);
    col_rot_[c] = R.cast<float>();
  }
  R = Rm;
  for (int c = cm - 1; c >= 0; --c) {
    R = step(R, col_t_[c + 1], col_t_[c]);  // backwards in time: negative dt
    col_rot_[c] = R.cast<float>();
  }
  return true;
}

bool Segmenter::prepare(const Scan& scan) {
  out_.height = scan.height;
  out_.width = scan.width;
  auto fail = [&](SegStatus st, std::string why) {
    out_.status = st;
    out_.status_text = std::move(why);
    return false;
  };
  if (scan.height <= 0 || scan.width <= 0) return fail(SegStatus::kEmpty, "empty scan (no rows/columns)");
  const size_t n = size_t(scan.height) * scan.width;
  if (scan.range_mm.size() != n)
    return fail(SegStatus::kBadInput, "range_mm has " + std::to_string(scan.range_mm.size()) + " pixels, expected " +
                                          std::to_string(scan.height) + "x" + std::to_string(scan.width));
  if (scan.beams.beams() != scan.height || int(scan.beams.azimuth_deg.size()) != scan.height)
    return fail(SegStatus::kBadInput, "beam intrinsics have " + std::to_string(scan.beams.beams()) +
                                          " beams but the scan has " + std::to_string(scan.height) + " rows");
  if (scan.height < 4) return fail(SegStatus::kBadInput, "too few beams (" + std::to_string(scan.height) + ")");
  for (double a : scan.beams.altitude_deg)
    if (!std::isfinite(a) || std::abs(a) > 90) return fail(SegStatus::kBadInput, "beam altitude not finite or > 90 deg");
  for (double a : scan.beams.azimuth_deg)
    if (!std::isfinite(a)) return fail(SegStatus::kBadInput, "beam azimuth not finite");

  if (lut_width_ != scan.width || !same_beams(lut_beams_, scan.beams)) {
    lut_ = make_xyz_lut(scan.beams, scan.width);
    lut_beams_ = scan.beams;
    lut_width_ = scan.width;
    ring_order_.resize(scan.height);
    std::iota(ring_order_.begin(), ring_order_.end(), 0);
    std::stable_sort(ring_order_.begin(), ring_order_.end(),
                     [&](int a, int b) { return scan.beams.altitude_deg[a] > scan.beams.altitude_deg[b]; });
  }
  xyz_.resize(n);
  range_.resize(n);
  // Rotation de-skew: a return measured at column time t_c is rotated into the sensor frame at mid-sweep,
  // p_mid = R_mid<-c p, R integrated from the gyro (body frame = sensor frame; see deskew_rotations()).
  // Only rotation matters for the planes: yaw rate leaves heights unchanged, roll/pitch rates tilt them (a few tenths of a degree per sweep when the platform wobbles, worst in corridors where the
  // ceiling is seen in two short azimuth windows). Translation during the sweep shifts heights by
  // v_z * 0.05 s (mm). Wall points are published as measured (with their times): downstream compensates.
  const bool deskew = deskew_rotations(scan);
  out_.deskewed = deskew;
  if (deskew) raw_.resize(n);
  // Range gate in integers: float(r) < rmin || float(r) > rmax for the 20-bit ranges (exact in float).
  const float rmin = float(cfg_.min_range_m * 1000.0), rmax = float(cfg_.max_range_m * 1000.0);
  const uint32_t r_lo = uint32_t(std::clamp(std::ceil(double(rmin)), 1.0, 4294967295.0));
  const uint32_t r_hi = uint32_t(std::clamp(std::floor(double(rmax)), 0.0, 4294967295.0));
  // Per column (once, not per pixel): look-up column (measurement id) and validity.
  const int W = scan.width, H = scan.height;
  const bool mids = int(scan.measurement_id.size()) == W;
  const bool cvalid = int(scan.column_valid.size()) == W;
  col_mid_.resize(W);
  col_ok_.resize(W);
  for (int c = 0; c < W; ++c) {
    int mid = mids ? scan.measurement_id[c] : c;
    if (mid < 0 || mid >= W) mid = c;
    col_mid_[c] = mid;
    col_ok_[c] = !(cvalid && !scan.column_valid[c]);
  }
  // XYZ of every valid pixel, and in the same pass the candidate sets: upper half rings (top first) and
  // lower half rings (bottom first), each ring in column order (an odd middle ring is in neither).
  size_t valid = 0;
  auto ring_pass = [&](int u, Candidates* cs) {
    const size_t row = size_t(u) * W;
    for (int c = 0; c < W; ++c) {
      const size_t i = row + c;
      const uint32_t r = scan.range_mm[i];
      if (r < r_lo || r > r_hi || !col_ok_[c]) {
        range_[i] = 0.f;
        continue;
      }
      const size_t k = row + col_mid_[c];
      Eigen::Vector3f p = lut_.direction.row(k).transpose() * float(r) + lut_.offset.row(k).transpose();
      if (deskew) {
        raw_[i] = p;
        p = col_rot_[c] * p;
      }
      xyz_[i] = p;
      const float rm = float(r) * 1e-3f;
      range_[i] = rm;
      ++valid;
      if (cs) {
        cs->p.push_back(p);
        cs->range.push_back(rm);
        cs->pixel.push_back(int32_t(i));
      }
    }
    if (cs) cs->ring_start.push_back(int32_t(cs->p.size()));
  };
  for (Candidates* cs : {&upper_, &lower_}) {
    cs->p.clear();
    cs->range.clear();
    cs->pixel.clear();
    cs->ring_start.assign(1, 0);
    cs->width = W;
  }
  const int half = H / 2;
  for (int k = 0; k < half; ++k) ring_pass(ring_order_[k], &upper_);
  for (int k = 0; k < half; ++k) ring_pass(ring_order_[H - 1 - k], &lower_);
  if (H % 2 == 1) ring_pass(ring_order_[half], nullptr);
  if (valid == 0) return fail(SegStatus::kEmpty, "no valid returns in the scan");
  return true;
}

void Segmenter::quality(const Candidates& c, Plane& pl) const {
  const Eigen::Vector3f n = pl.coeffs.head<3>().cast<float>();
  const float d = float(pl.coeffs[3]);
  const float thr = float(cfg_.inlier_threshold_m);
  double r2 = 0;
  int cnt = 0, beyond = 0;
  const float beyond_thr = 2 * thr;
  Eigen::Vector3f reff = Eigen::Vector3f::Zero();
  bool have_ref = false;
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  for (size_t i = 0; i < c.p.size(); ++i) {
    const float r = n.dot(c.p[i]) + d;
    if (r < -beyond_thr) ++beyond;
    if (std::abs(r) >= thr) continue;
    if (!have_ref) {
      reff = c.p[i];
      have_ref = true;
    }
    const double x = c.p[i].x() - reff.x(), y = c.p[i].y() - reff.y(), z = c.p[i].z() - reff.z();
    sx += x; sy += y; sz += z;
    sxx += x * x; sxy += x * y; sxz += x * z; syy += y * y; syz += y * z; szz += z * z;
    r2 += double(r) * r;
    ++cnt;
  }
  Moments m;
  m.w = cnt;
  m.s << sx, sy, sz;
  m.ss << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  const Eigen::Vector3d ref = reff.cast<double>();
  pl.inliers = cnt;
  pl.beyond = beyond;
  pl.rms_m = cnt ? std::sqrt(r2 / cnt) : 0.0;
  if (cnt < 3) return;
  Eigen::Vector4d tmp;
  Eigen::Vector3d ev;
  m.plane(ref, -pl.coeffs.head<3>(), tmp, &ev);
  // Normal uncertainty ~ sigma / sqrt(smallest in-plane scatter); distance ~ sigma / sqrt(N) plus the lever
  // arm from the inlier centroid to the sensor.
  const double sig = std::max(pl.rms_m, 1e-4);
  pl.tilt_sigma = sig / std::sqrt(std::max(ev[1], 1e-9));
  const Eigen::Vector3d cen = m.s / m.w + ref;
  const Eigen::Vector3d nn = pl.coeffs.head<3>();
  const double lever = (cen - nn.dot(cen) * nn).norm();
  pl.d_sigma = std::hypot(sig / std::sqrt(double(cnt)), lever * pl.tilt_sigma);
}

void Segmenter::update_room_height(double h) {
  heights_.push_back(h);
  while (int(heights_.size()) > std::max(1, cfg_.room_height_window)) heights_.pop_front();
  std::vector<double> v(heights_.begin(), heights_.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  room_height_ = v[v.size() / 2];
}

double Segmenter::mid_sweep_offset(const Scan& scan) {
  // Halfway between the first and the last valid column time (0 without column times).
  const bool cvalid = scan.column_valid.size() == scan.column_utime.size();
  int64_t t0 = 0, t1 = 0;
  for (size_t c = 0; c < scan.column_utime.size(); ++c) {
    const int64_t t = scan.column_utime[c];
    if (t == 0 || (cvalid && !scan.column_valid[c])) continue;
    if (t0 == 0 || t < t0) t0 = t;
    t1 = std::max(t1, t);
  }
  return t0 == 0 ? 0.0 : 1e-6 * double(t0 + (t1 - t0) / 2 - scan.utime);
}

const Segmentation& Segmenter::process(const Scan& scan) {
  out_.utime = scan.utime;
  out_.attitude_t = mid_sweep_offset(scan);
  out_.seq = scan.seq;
  out_.status = SegStatus::kOk;
  out_.status_text.clear();
  out_.ceiling = Plane{};
  out_.ground = Plane{};
  out_.wall.clear();
  out_.label.clear();

  // Gravity prior: IMU (when enabled and available), else the sensor's z axis.
  bool imu_now = false;
  if (accel_n_ > 0) {
    imu_up_ = (accel_sum_ / accel_n_).normalized();
    have_imu_ = true;
    accel_sum_.setZero();
    accel_n_ = 0;
  }
  if (cfg_.use_imu_prior && have_imu_) imu_now = true;
  const Eigen::Vector3d gate_up = imu_now ? imu_up_ : Eigen::Vector3d::UnitZ();

  auto fallback_attitude = [&]() {
    if (imu_now) {
      roll_pitch_from_up(imu_up_, out_.roll, out_.pitch);
      out_.roll_pitch_sigma = 0.5 * kDeg;
      out_.attitude_source = AttitudeSource::kImu;
    } else if (have_prev_attitude_) {
      out_.roll = prev_roll_;
      out_.pitch = prev_pitch_;
      out_.roll_pitch_sigma = std::max(prev_rp_sigma_ * 2.0, 0.2 * kDeg);
      out_.attitude_source = AttitudeSource::kPrevious;
    } else {
      out_.roll = out_.pitch = 0;
      out_.roll_pitch_sigma = M_PI;
      out_.attitude_source = AttitudeSource::kNone;
    }
    if (have_prev_attitude_) {
      out_.z = prev_z_;
      out_.z_sigma = std::max(prev_z_sigma_ * 2.0, 0.05);
    } else {
      out_.z = 0;
      out_.z_sigma = 1e3;
    }
  };

  if (!prepare(scan)) {
    fallback_attitude();
    return out_;
  }
  if (scan.status == ScanStatus::kBadInput) {
    out_.status = SegStatus::kBadInput;
    out_.status_text = "scan marked bad by the driver";
    fallback_attitude();
    return out_;
  }
  if (keep_labels_) out_.label.assign(size_t(scan.height) * scan.width, 0);

  const double max_tilt = cfg_.max_tilt_deg * kDeg;
  const Eigen::Vector3d init_up =
      imu_now ? imu_up_ : (have_prev_ceiling_ ? Eigen::Vector3d(-prev_ceiling_.head<3>()) : gate_up);

  // Ceiling.
  {
    Eigen::Vector4d pl;
    std::string why;
    tighten_ = true;
    const bool fitted = fit_plane(upper_, init_up, have_prev_ceiling_ ? &prev_ceiling_ : nullptr, pl);
    tighten_ = false;
    if (!fitted) {
      why = "no plane fit on the upper rings";
    } else {
      out_.ceiling.coeffs = pl;
      quality(upper_, out_.ceiling);
      const double tilt = std::acos(std::clamp(-pl.head<3>().dot(gate_up), -1.0, 1.0));
      if (tilt > max_tilt)
        why = "ceiling tilted " + std::to_string(tilt / kDeg) + " deg > max_tilt_deg";
      else if (pl[3] < 0.2)
        why = "ceiling plane not above the sensor";
      else if (out_.ceiling.inliers < cfg_.min_plane_inliers)
        why = "ceiling has " + std::to_string(out_.ceiling.inliers) + " inliers < " +
              std::to_string(cfg_.min_plane_inliers);
      else if (out_.ceiling.beyond > cfg_.max_beyond_ratio * out_.ceiling.inliers)
        why = "ceiling not where the rays end: " + std::to_string(out_.ceiling.beyond) + " returns beyond it vs " +
              std::to_string(out_.ceiling.inliers) + " inliers";
      else if (out_.ceiling.inliers < cfg_.min_inlier_fraction * double(upper_.p.size()))
        why = "ceiling inliers are only " + std::to_string(100.0 * out_.ceiling.inliers / upper_.p.size()) +
              " % of the upper-ring returns";
    }
    out_.ceiling.found = why.empty();
    if (!why.empty()) {
      out_.status = SegStatus::kNoCeiling;
      out_.status_text = why;
    }
  }
  const Eigen::Vector3d up =
      out_.ceiling.found ? Eigen::Vector3d(-out_.ceiling.coeffs.head<3>()) : init_up.normalized();

  // Ground: the same fit on the lower rings, flipped.
  {
    Eigen::Vector4d pl;
    if (fit_plane(lower_, -up, have_prev_ground_ ? &prev_ground_ : nullptr, pl)) {
      out_.ground.coeffs = pl;
      quality(lower_, out_.ground);
      const double tilt = std::acos(std::clamp(pl.head<3>().dot(up), -1.0, 1.0));
      out_.ground.found = tilt < std::min(max_tilt, 5 * kDeg) && pl[3] > 0.1 &&
                          out_.ground.inliers >= cfg_.min_plane_inliers &&
                          out_.ground.beyond <= cfg_.max_beyond_ratio * out_.ground.inliers;
    }
  }

  // Height: sensor height above the floor = room height - distance to the ceiling.
  if (out_.ceiling.found && out_.ground.found && cfg_.ceiling_height_m <= 0)
    update_room_height(out_.ceiling.distance() + out_.ground.distance());
  const double H = cfg_.ceiling_height_m > 0 ? cfg_.ceiling_height_m : room_height_;

  if (out_.ceiling.found) {
    roll_pitch_from_up(up, out_.roll, out_.pitch);
    out_.roll_pitch_sigma = out_.ceiling.tilt_sigma;
    out_.attitude_source = AttitudeSource::kCeiling;
    if (H > 0) {
      out_.z = H - out_.ceiling.distance();
      out_.z_sigma = out_.ceiling.d_sigma + (cfg_.ceiling_height_m > 0 ? 0.0 : out_.ground.d_sigma / std::sqrt(double(heights_.size())));
    } else if (out_.ground.found) {
      out_.z = out_.ground.distance();
      out_.z_sigma = out_.ground.d_sigma;
    } else {
      out_.z = have_prev_attitude_ ? prev_z_ : 0.0;
      out_.z_sigma = have_prev_attitude_ ? std::max(prev_z_sigma_ * 2.0, 0.05) : 1e3;
    }
    have_prev_attitude_ = true;
    prev_roll_ = out_.roll;
    prev_pitch_ = out_.pitch;
    prev_z_ = out_.z;
    prev_rp_sigma_ = out_.roll_pitch_sigma;
    prev_z_sigma_ = out_.z_sigma;
    have_prev_ceiling_ = true;
    prev_ceiling_ = out_.ceiling.coeffs;
    update_gyro_bias(up);
  } else {
    have_bias_ref_ = false;
    fallback_attitude();
    if (out_.ground.found) {
      out_.z = out_.ground.distance();
      out_.z_sigma = out_.ground.d_sigma;
    }
  }
  if (out_.ground.found) {
    have_prev_ground_ = true;
    prev_ground_ = out_.ground.coeffs;
  }

  select_walls(scan, up);
  return out_;
}

void Segmenter::select_walls(const Scan& scan, const Eigen::Vector3d& up) {
  // Upper bound: the ceiling (this frame's or last known); lower bound: the ground plane, else a plane
  // parallel to the ceiling one room height below, else last known ground.
  Eigen::Vector4d ceil, floor;
  double mc = cfg_.wall_margin_m, mf = cfg_.wall_margin_m;
  if (out_.ceiling.found) {
    ceil = out_.ceiling.coeffs;
    mc = std::max(mc, 3.0 * out_.ceiling.rms_m);
  } else if (have_prev_ceiling_) {
    ceil = prev_ceiling_;
    mc *= 1.5;
  } else {
    if (!out_.status_text.empty()) out_.status_text += "; ";
    out_.status_text += "no ceiling known: no wall points";
    return;
  }
  const double H = cfg_.ceiling_height_m > 0 ? cfg_.ceiling_height_m : room_height_;
  if (out_.ground.found) {
    floor = out_.ground.coeffs;
    mf = std::max(mf, 3.0 * out_.ground.rms_m);
  } else if (H > 0) {
    floor << -ceil.head<3>(), H - ceil[3];
  } else if (have_prev_ground_) {
    floor = prev_ground_;
    mf *= 1.5;
  } else {
    floor << up, ceil[3];  // last resort: assume the sensor at mid height
  }
  const Eigen::Vector3f nc = ceil.head<3>().cast<float>(), nf = floor.head<3>().cast<float>();
  const float dc = float(ceil[3] - mc), df = float(floor[3] - mf);
  const float cin = float(ceil[3] - cfg_.inlier_threshold_m), fin = float(floor[3] - cfg_.inlier_threshold_m);
  const int W = scan.width;
  auto& w = out_.wall;
  const size_t cap = size_t(scan.height) * W;
  w.x.reserve(cap); w.y.reserve(cap); w.z.reserve(cap); w.range.reserve(cap); w.t.reserve(cap); w.ring.reserve(cap); w.column.reserve(cap);
  // Column time offsets (staggered column = measurement order), for motion compensation downstream.
  col_dt_.assign(W, 0.f);
  if (scan.column_utime.size() == size_t(W))
    for (int v = 0; v < W; ++v)
      if (scan.column_utime[v] != 0) col_dt_[v] = float(double(scan.column_utime[v] - scan.utime) * 1e-6);
  for (int u = 0; u < scan.height; ++u) {
    const int shift = u < int(scan.beams.pixel_shift_by_row.size()) ? scan.beams.pixel_shift_by_row[u] : 0;
    int v = ((-shift) % W + W) % W;  // staggered column of destaggered column cd (cd - shift mod W)
    for (int cd = 0; cd < W; ++cd, ++v) {
      if (v == W) v = 0;
      const size_t i = size_t(u) * W + v;
      const float r = range_[i];
      if (r <= 0.f) continue;
      const Eigen::Vector3f& p = xyz_[i];
      const float sc = nc.dot(p), sf = nf.dot(p);
      if (sc > -dc && sf > -df) {
        w.push(out_.deskewed ? raw_[i] : p, r, u, cd, col_dt_[v]);  // as measured (see prepare())
        if (keep_labels_) out_.label[i] = 3;
      } else if (keep_labels_) {
        if (sc <= -cin) out_.label[i] = 1;
        else if (sf <= -fin) out_.label[i] = 2;
      }
    }
  }
}

// ---- the paper's ring-based robust fit ---------------------------------------------------------------
bool RingSegmenter::fit_plane(const Candidates& c, const Eigen::Vector3d& up_in, const Eigen::Vector4d* previous,
                              Eigen::Vector4d& plane) {
  if (c.p.size() < 10 || c.rings() < 1) return false;
  const Eigen::Vector3d up = up_in.normalized();
  const Eigen::Vector3f upf = up.cast<float>();
  Eigen::Vector3d e1, e2;
  basis(up, e1, e2);

  // 1. Seeds: on each of the K_r outermost rings, the largest-range point of every azimuth sector, keeping
  //    the largest fraction of those (obstructed rays are shorter), and only points above the sensor.
  const int S = std::max(4, cfg_.seed_sectors);
  seeds_.clear();
  all_seeds_.clear();
  const int kr = std::min(std::max(1, cfg_.seed_rings), c.rings());
  for (int k = 0; k < kr; ++k) {
    sector_best_.assign(S, -1.f);
    sector_idx_.assign(S, -1);
    for (int i = c.ring_start[k]; i < c.ring_start[k + 1]; ++i) {
      if (upf.dot(c.p[i]) < 0.2f) continue;
      const int col = c.pixel[i] % c.width;
      const int s = col * S / c.width;
      if (c.range[i] > sector_best_[s]) {
        sector_best_[s] = c.range[i];
        sector_idx_[s] = i;
      }
    }
    std::vector<int> cand;
    for (int s = 0; s < S; ++s)
      if (sector_idx_[s] >= 0) cand.push_back(sector_idx_[s]);
    std::sort(cand.begin(), cand.end(), [&](int a, int b) { return c.range[a] > c.range[b]; });
    const size_t keep = std::min(cand.size(), std::max<size_t>(3, size_t(std::ceil(cfg_.seed_fraction * S))));
    seeds_.insert(seeds_.end(), cand.begin(), cand.begin() + keep);
    all_seeds_.insert(all_seeds_.end(), cand.begin(), cand.end());
  }

  // 2. Initial plane by linear regression h = a*x1 + b*x2 + g in the prior's frame, trimmed twice.
  bool have_seed_plane = false;
  Eigen::Vector4d seed_plane;
  std::vector<float> res;
  for (int round = 0; round < 3 && seeds_.size() >= 3; ++round) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (int i : seeds_) {
      const Eigen::Vector3d p = c.p[i].cast<double>();
      const Eigen::Vector3d x(p.dot(e1), p.dot(e2), 1.0);
      A.noalias() += x * x.transpose();
      b += x * p.dot(up);
    }
    const Eigen::Vector3d sol = A.ldlt().solve(b);
    if (!sol.allFinite()) break;
    const Eigen::Vector3d m = up - sol[0] * e1 - sol[1] * e2;
    const double nm = m.norm();
    seed_plane << -m / nm, sol[2] / nm;
    have_seed_plane = true;
    if (round == 2) break;
    res.clear();
    for (int i : seeds_) res.push_back(std::abs(float(seed_plane.head<3>().dot(c.p[i].cast<double>()) + seed_plane[3])));
    std::vector<float> tmp = res;
    const double thr = std::max(0.05, 3.0 * 1.4826 * median_inplace(tmp));
    std::vector<int> kept;
    for (size_t j = 0; j < seeds_.size(); ++j)
      if (res[j] <= thr) kept.push_back(seeds_[j]);
    if (kept.size() < 3 || kept.size() == seeds_.size()) break;
    seeds_.swap(kept);
  }

  // Choose the start with the most support on a subsample of all half-ring points: the seed regression,
  // last frame's plane, or planes through seed triplets (deterministic sampling). The triplets make the
  // start robust when a tilted sensor's longest rays hit far walls, not the ceiling.
  //
  // Support = soft inlier count (MSAC: 1 - (r/T)^2 for |r| < T, T = inlier_threshold_m) minus
  // (1 / max_beyond_ratio) per return more than 2T *beyond* the plane: a ceiling is where the rays end, so
  // a plane cutting through walls (many "inliers" at one height in a corridor) loses, and a plane the
  // acceptance test would reject (beyond > max_beyond_ratio x inliers) scores below zero. The soft count
  // prefers the tight fit over a loose plane that merely stays within T of a narrow ceiling strip.
  const double max_tilt = cfg_.max_tilt_deg * M_PI / 180.0;
  const float thr = float(cfg_.inlier_threshold_m), beyond_thr = 2 * thr;
  const float beyond_weight = float(1.0 / std::max(1e-3, cfg_.max_beyond_ratio));
  auto score_band = [&](const Eigen::Vector4d& pl, size_t stride, float band) {
    const Eigen::Vector3f n = pl.head<3>().cast<float>();
    const float d = float(pl[3]), inv_b2 = 1.f / (band * band);
    float soft = 0.f;
    int beyond = 0;
    for (size_t i = 0; i < c.p.size(); i += stride) {
      const float r = n.dot(c.p[i]) + d;
      soft += max0(1.f - r * r * inv_b2);
      beyond += r < -beyond_thr;
    }
    return double(soft - beyond_weight * float(beyond)) * double(stride);
  };
  auto score = [&](const Eigen::Vector4d& pl, size_t stride) { return score_band(pl, stride, thr); };
  constexpr size_t kStartStride = 24;  // start selection: ~1.4k of 32k half-ring returns
  Eigen::Vector4d cur;
  double best = -std::numeric_limits<double>::infinity();
  bool have_start = false;
  auto consider = [&](const Eigen::Vector4d& pl) {
    if (!pl.allFinite() || -pl.head<3>().dot(up) < std::cos(max_tilt) || pl[3] <= 0) return;
    const double sc = score(pl, kStartStride);
    if (!have_start || sc > best) {
      best = sc;
      cur = pl;
      have_start = true;
    }
  };
  if (have_seed_plane) consider(seed_plane);
  if (previous) consider(*previous);
  uint32_t state = 12345u;
  auto next = [&]() {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  for (int t = 0; t < cfg_.seed_triplets; ++t) {
    // Alternate between the longest-range seeds (the paper's) and all sector maxima (tilted sensor).
    const std::vector<int>& pool = (t % 2 == 0) ? seeds_ : all_seeds_;
    if (pool.size() < 3) continue;
    {
      const Eigen::Vector3d a = c.p[pool[next() % pool.size()]].cast<double>();
      const Eigen::Vector3d b = c.p[pool[next() % pool.size()]].cast<double>();
      const Eigen::Vector3d q = c.p[pool[next() % pool.size()]].cast<double>();
      Eigen::Vector3d nn = (b - a).cross(q - a);
      if (nn.norm() < 1e-3) continue;
      nn.normalize();
      if (nn.dot(up) > 0) nn = -nn;
      Eigen::Vector4d pl;
      pl << nn, -nn.dot(a);
      consider(pl);
    }
  }
  if (!have_start) return false;

  // 3. M-estimator (IRLS, Tukey biweight) over all points of the half rings, cut-off shrinking from
  //    irls_initial_scale_m to ~4.7 robust sigmas of the inliers. The start already has its support within
  //    T = 5 cm, so the first cut-off only needs to cover its tilt error over the far ceiling (0.2 m); a wide
  //    one (0.5 m) lets the band of wall returns below a corridor ceiling (10x the ceiling returns there)
  //    dominate the first weighted fit, which then converges to a plane through the walls.
  double last_sigma = 0;  // robust residual scale of the last refinement's final iteration
  auto refine = [&](Eigen::Vector4d cur, double first_cut, double min_cut, bool fixed) -> std::optional<Eigen::Vector4d> {
  const Eigen::Vector3d ref = -cur[3] * cur.head<3>();  // a point of the plane (numerics)
  const Eigen::Vector3f reff = ref.cast<float>();
  double cut = first_cut;
  band_.clear();  // the band's points, contiguous (streamed by every iteration)
  {
    const Eigen::Vector3f n = cur.head<3>().cast<float>();
    const float d = float(cur[3]), cb = float(cut);
    for (size_t i = 0; i < c.p.size(); ++i)
      if (std::abs(n.dot(c.p[i]) + d) < cb) band_.push_back(c.p[i]);
  }
  if (band_.size() < 3) return std::nullopt;
  for (int it = 0; it < std::max(1, cfg_.irls_iterations); ++it) {
    const Eigen::Vector3f n = cur.head<3>().cast<float>();
    const float d = float(cur[3]);
    // Residuals once per iteration; robust scale (1.4826 * median |r| inside the cut-off) from a histogram.
    res_.resize(band_.size());
    constexpr int kBins = 256;
    int hist[kBins] = {0};
    const float inv_bin = float(kBins / cut);
    int inside = 0;
    for (size_t j = 0; j < band_.size(); ++j) {
      const float r = n.dot(band_[j]) + d;
      res_[j] = r;
      const float a = std::abs(r);
      if (a < cut) {
        ++hist[std::min(kBins - 1, int(a * inv_bin))];
        ++inside;
      }
    }
    if (inside < 3) return std::nullopt;
    int acc = 0, bin = 0;
    for (; bin < kBins; ++bin) {
      acc += hist[bin];
      if (2 * acc >= inside) break;
    }
    const double sigma = 1.4826 * (bin + 0.5) / inv_bin;
    last_sigma = sigma;
    const double next_cut = fixed ? cut : std::max({cut * 0.5, 4.685 * sigma, min_cut});
    const bool final_scale = next_cut >= cut;
    cut = std::min(cut, next_cut);
    const float inv_c2 = float(1.0 / (cut * cut));
    // While the cut-off still shrinks a subsample is enough; at the final scale use every point.
    const size_t step = final_scale ? 1 : 3;
    double sw = 0, sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
    for (size_t j = 0; j < band_.size(); j += step) {
      const float r = res_[j];
      const float t = r * r * inv_c2;
      if (t >= 1.f) continue;
      const double w = (1.f - t) * (1.f - t);
      const Eigen::Vector3f& pf = band_[j];
      const double x = pf.x() - reff.x(), y = pf.y() - reff.y(), z = pf.z() - reff.z();
      sw += w;
      sx += w * x; sy += w * y; sz += w * z;
      sxx += w * x * x; sxy += w * x * y; sxz += w * x * z;
      syy += w * y * y; syz += w * y * z; szz += w * z * z;
    }
    Moments m;
    m.w = sw;
    m.s << sx, sy, sz;
    m.ss << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
    Eigen::Vector4d next;
    if (!m.plane(ref, up, next)) return std::nullopt;
    const double dn = (next.head<3>() - cur.head<3>()).norm(), dd = std::abs(next[3] - cur[3]);
    cur = next;
    if (final_scale && dn < 1e-5 && dd < 1e-4) break;  // 0.0006 deg, 0.1 mm
  }
  return cur;
  };
  // Refine the best start and, when it was not last frame's plane, last frame's plane too. A refinement
  // that lowers the support (T band, dense subsample) diverged (walls captured it): its start is kept
  // instead. Of the two, keep the one with the higher support with the soft band narrowed to 3 robust
  // sigmas of the tighter fit (>= 1 cm): at T = 5 cm a plane tilted a few tenths of a degree through a
  // narrow corridor ceiling plus the wall tops below it scores as well as the true one; at 3 sigma it
  // loses the ceiling returns it leaves behind. (A lowered/sloped patch must not capture it either.)
  constexpr size_t kFinalStride = 3;
  struct Fit {
    Eigen::Vector4d pl;
    double sigma;
  };
  auto refine_guarded = [&](const Eigen::Vector4d& start) -> std::optional<Fit> {
    const auto r = refine(start, cfg_.irls_initial_scale_m, 0.02, false);
    if (r && score(*r, kFinalStride) >= score(start, kFinalStride)) return Fit{*r, last_sigma};
    return Fit{start, cfg_.inlier_threshold_m / 3};
  };
  std::optional<Fit> res1 = refine_guarded(cur);
  if (previous && (cur - *previous).norm() > 1e-9) {
    const std::optional<Fit> res2 = refine_guarded(*previous);
    if (res2 && res1) {
      const float t_sel = float(std::clamp(3.0 * std::min(res1->sigma, res2->sigma), 0.01, cfg_.inlier_threshold_m));
      if (score_band(res2->pl, kFinalStride, t_sel) > score_band(res1->pl, kFinalStride, t_sel)) res1 = res2;
    } else if (res2) {
      res1 = res2;
    }
  }
  // Ceiling only: a refit at a fixed cut-off of tight_refit_sigmas robust sigmas (>= 1 cm) of the result.
  // Where two surfaces meet (a sloped ceiling patch next to the flat ceiling) the Tukey fit at 4.7 sigma
  // settles on a compromise tilted a few tenths of a degree between them; at ~2.5 sigma only the dominant
  // surface keeps its support. The tighter of the two wins on the narrow-band support.
  if (res1 && tighten_ && cfg_.tight_refit_sigmas > 0) {
    const double ct = std::max(cfg_.tight_refit_sigmas * res1->sigma, 0.01);
    if (const auto r = refine(res1->pl, ct, ct, true)) {
      const Fit tight{*r, last_sigma};
      const float t_sel = float(std::clamp(3.0 * std::min(res1->sigma, tight.sigma), 0.01, cfg_.inlier_threshold_m));
      if (score_band(tight.pl, kFinalStride, t_sel) > score_band(res1->pl, kFinalStride, t_sel)) res1 = tight;
    }
  }
  if (!res1) return false;
  plane = res1->pl;
  return true;
}

}  // namespace fploc::seg
