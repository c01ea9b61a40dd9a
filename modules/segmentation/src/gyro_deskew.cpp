#include "fploc/segmentation/gyro_deskew.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "segmenter_constants.h"

namespace fploc::seg {

void GyroDeskew::add(const Eigen::Vector3d& w, int64_t utime) {
  if (!w.allFinite() || w.norm() > k::kMaxGyroRate || utime <= 0) return;
  if (!gyro_.empty() && utime <= gyro_.back().first) {
    if (utime < gyro_.back().first - k::kGyroKeepUs) gyro_.clear();  // time went back: a new log/sensor
    else return;                                                      // duplicate or out of order: ignore
  }
  gyro_.emplace_back(utime, w);
  while (gyro_.size() > 2 && gyro_.front().first < utime - k::kGyroKeepUs) gyro_.pop_front();
}

Eigen::Vector3d GyroDeskew::rate_at(int64_t t) const {
  // Each sample is the mean rate over the interval since the previous sample (a band-limited IMU output, as
  // the OS-1's and the simulator's): the rate at t is the sample whose interval holds t (interpolating
  // between samples would shift it by half an interval); the nearest sample outside their span; minus the
  // estimated bias.
  if (t <= gyro_.front().first) return gyro_.front().second - gyro_bias_;
  if (t >= gyro_.back().first) return gyro_.back().second - gyro_bias_;
  auto it = std::lower_bound(gyro_.begin(), gyro_.end(), t,
                             [](const std::pair<int64_t, Eigen::Vector3d>& s, int64_t v) { return s.first < v; });
  return it->second - gyro_bias_;
}

Eigen::Vector3d GyroDeskew::rate_walk(int64_t t, size_t& at) const {
  // The first sample at or after t (the last one when none is), as rate_at's search finds it.
  const size_t n = gyro_.size();
  at = std::min(at, n - 1);
  while (at + 1 < n && gyro_[at].first < t) ++at;
  while (at > 0 && gyro_[at - 1].first >= t) --at;
  return gyro_[at].second - gyro_bias_;
}

bool GyroDeskew::covers(int64_t ta, int64_t tb) const {
  // Samples from before ta to after tb (within kGyroEdgeUs) without a gap longer than kGyroMaxGapUs.
  if (gyro_.size() < 2 || gyro_.front().first > ta + k::kGyroEdgeUs || gyro_.back().first < tb - k::kGyroEdgeUs)
    return false;
  int64_t prev = gyro_.front().first;
  for (const auto& g : gyro_) {
    if (g.first > tb + k::kGyroMaxGapUs) break;
    if (g.first >= ta - k::kGyroMaxGapUs && g.first - prev > k::kGyroMaxGapUs) return false;
    prev = g.first;
  }
  return true;
}

Eigen::Matrix3d GyroDeskew::rotation(int64_t ta, int64_t tb) const {
  // Orientation at tb relative to ta (body frame), midpoint rule in steps of at most kGyroStepUs.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  const int steps = int(std::max<int64_t>(1, (std::abs(tb - ta) + k::kGyroStepUs - 1) / k::kGyroStepUs));
  for (int s = 0; s < steps; ++s) {
    const int64_t a = ta + (tb - ta) * s / steps, b = ta + (tb - ta) * (s + 1) / steps;
    const Eigen::Vector3d th = rate_at(a + (b - a) / 2) * (1e-6 * double(b - a));
    const double ang = th.norm();
    if (ang > 0) R = R * Eigen::AngleAxisd(ang, th / ang).toRotationMatrix();
  }
  return R;
}

void GyroDeskew::update_bias(const Eigen::Vector3d& up) {
  // Gyro bias (the part perpendicular to gravity, the one that tilts the de-skew) from consecutive
  // ceilings: the up vector of the previous frame carried to this mid-sweep by the (bias-corrected) gyro
  // should be this frame's up; a residual rotation rate delta = (u_pred x u) / dt is bias left over.
  // Low-pass (a few seconds); steps of more than kBiasMaxStep (a wrong plane) are ignored.
  const int64_t t = sweep_tm_;
  if (t == 0 || !enabled_) {
    have_bias_ref_ = false;
    return;
  }
  if (have_bias_ref_ && t > bias_ref_t_ && t - bias_ref_t_ <= k::kBiasMaxDtUs && covers(bias_ref_t_, t)) {
    const double dt = 1e-6 * double(t - bias_ref_t_);
    const Eigen::Vector3d u_pred = rotation(bias_ref_t_, t).transpose() * bias_ref_up_;
    const Eigen::Vector3d delta = u_pred.cross(up) / dt;
    if (delta.norm() < k::kBiasMaxStep) gyro_bias_ += k::kBiasGain * delta;
  }
  have_bias_ref_ = true;
  bias_ref_t_ = t;
  bias_ref_up_ = up;
}

bool GyroDeskew::prepare(const Scan& scan) {
  // Orientation at each column time relative to mid-sweep, R_mid<-c = prod exp([w dt]x), integrated
  // column by column (midpoint rate, linearly interpolated gyro). Needs gyro samples covering the sweep
  // (within kGyroEdgeUs of both ends) and increasing column times.
  const int W = scan.width;
  sweep_tm_ = 0;
  if (!enabled_ || gyro_.size() < 2 || int(scan.column_utime.size()) != W) return false;
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
  if (t1 - t0 > k::kMaxSweepUs) return false;
  if (gyro_.front().first > t0 + k::kGyroEdgeUs || gyro_.back().first < t1 - k::kGyroEdgeUs) return false;
  // Column times (invalid columns take the previous column's time: they carry no returns anyway).
  col_t_.resize(W);
  int64_t last = t0;
  for (int c = 0; c < W; ++c) {
    if (c >= c0 && c <= c1 && scan.column_utime[c] != 0 && !(cvalid && !scan.column_valid[c])) last = scan.column_utime[c];
    col_t_[c] = last;
  }
  const int64_t tm = t0 + (t1 - t0) / 2;
  sweep_tm_ = tm;  // the gyro covers this sweep (planes refer to mid-sweep)
  // Largest rotation over half a sweep: skip the work when it is below kMinDeskewRad.
  double peak = 0;
  for (const auto& g : gyro_)
    if (g.first >= t0 - k::kGyroEdgeUs && g.first <= t1 + k::kGyroEdgeUs) peak = std::max(peak, g.second.norm());
  if (peak * 0.5e-6 * double(t1 - t0) < k::kMinDeskewRad) return false;
  col_rot_.resize(W);
  int cm = c0;
  while (cm < c1 && col_t_[cm] < tm) ++cm;
  // Columns are evenly spaced and the gyro's rate holds over a sample's interval: most consecutive steps rotate
  // by the same angle vector, whose matrix (a sine and a cosine) is kept. Two are kept: column times in whole
  // microseconds step by two alternating lengths (e.g. 97 and 98 us at 1024 columns x 10 Hz), so the angle
  // vectors alternate too within a gyro sample's interval.
  struct Inc {
    Eigen::Vector3d th = Eigen::Vector3d::Zero();
    Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
    bool turns = false;  // (a zero angle vector: no rotation)
  };
  Inc inc[2];
  int older = 0;  // the entry replaced next
  size_t at = 0;  // the gyro sample of the last step
  auto step = [&](const Eigen::Matrix3d& R, int64_t ta, int64_t tb) {
    const Eigen::Vector3d th = rate_walk(ta + (tb - ta) / 2, at) * (1e-6 * double(tb - ta));
    const Inc* e = th == inc[0].th ? &inc[0] : th == inc[1].th ? &inc[1] : nullptr;
    if (!e) {
      Inc& n = inc[older];
      older ^= 1;
      const double a = th.norm();
      n.th = th;
      n.turns = a > 0;
      if (n.turns) n.m = Eigen::AngleAxisd(a, th / a).toRotationMatrix();
      e = &n;
    }
    return e->turns ? Eigen::Matrix3d(R * e->m) : R;
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

}  // namespace fploc::seg
