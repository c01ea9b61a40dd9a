#include "fploc/segmentation/gyro_deskew.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "segmenter_constants.h"

namespace fploc::seg {

namespace {
constexpr int kDeskewBlockCols = 16;  // prepare(): columns integrated as one block (their rotations interpolated)
}  // namespace

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

inline const Eigen::Vector3d& GyroDeskew::sweep_rate_walk(int64_t t, size_t& at) const {
  // The first sample at or after t (the last one when none is), as rate_at's search finds it.
  const size_t n = sweep_rate_.size();
  at = std::min(at, n - 1);
  while (at + 1 < n && sweep_rate_[at].first < t) ++at;
  while (at > 0 && sweep_rate_[at - 1].first >= t) --at;
  return sweep_rate_[at].second;
}

Eigen::Matrix3f GyroDeskew::rotation_at(int c) const {
  Eigen::Matrix3f R;
  const float* g = rot_il_.data() + interleaved_offset(c);
  for (int e = 0; e < 9; ++e) R(e / 3, e % 3) = g[e * 8];
  return R;
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
  // Orientation at each column time relative to mid-sweep, R_mid<-c = prod exp([w dt]x) (midpoint rate, the
  // sample holding it), integrated block by block (below). Needs gyro samples covering the sweep
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
  // (through plain pointers, the test without branches: the same times)
  col_t_.resize(W);
  int64_t last = t0;
  const int64_t* ut = scan.column_utime.data();
  const uint8_t* cv = cvalid ? scan.column_valid.data() : nullptr;
  int64_t* ct = col_t_.data();
  for (int c = 0; c < W; ++c) {
    const bool take = (c >= c0) & (c <= c1) & (ut[c] != 0) & (!cv || cv[c] != 0);
    last = take ? ut[c] : last;
    ct[c] = last;
  }
  const int64_t tm = t0 + (t1 - t0) / 2;
  sweep_tm_ = tm;  // the gyro covers this sweep (planes refer to mid-sweep)
  // Largest rotation over half a sweep: skip the work when it is below kMinDeskewRad.
  double peak = 0;
  for (const auto& g : gyro_)
    if (g.first >= t0 - k::kGyroEdgeUs && g.first <= t1 + k::kGyroEdgeUs) peak = std::max(peak, g.second.norm());
  if (peak * 0.5e-6 * double(t1 - t0) < k::kMinDeskewRad) return false;
  rot_il_.resize(size_t((W + 7) / 8) * 72);
  float* const il = rot_il_.data();
  // Column c's entries (stride 8 in interleaved()).
  const auto at_col = [il](int c) { return il + interleaved_offset(c); };
  const auto put = [&](int c, const Eigen::Matrix3f& m) {
    float* g = at_col(c);
    for (int e = 0; e < 9; ++e) g[e * 8] = m(e / 3, e % 3);
  };
  // The samples the walks below can reach (for a time t in the sweep: the first sample at or after t, else the
  // last one), the bias subtracted once (the same difference rate_at forms per call).
  sweep_rate_.clear();
  {
    const int64_t lo_t = col_t_[0] < tm ? col_t_[0] : tm, hi_t = col_t_[size_t(W - 1)] > tm ? col_t_[size_t(W - 1)] : tm;
    auto it = std::lower_bound(gyro_.begin(), gyro_.end(), lo_t,
                               [](const std::pair<int64_t, Eigen::Vector3d>& g, int64_t v) { return g.first < v; });
    for (; it != gyro_.end(); ++it) {
      sweep_rate_.emplace_back(it->first, it->second - gyro_bias_);
      if (it->first >= hi_t) break;
    }
    if (sweep_rate_.empty()) sweep_rate_.emplace_back(gyro_.back().first, gyro_.back().second - gyro_bias_);
  }
  int cm = c0;
  while (cm < c1 && col_t_[cm] < tm) ++cm;
  // Integrated block by block (kDeskewBlockCols columns): a block's rotation is the product of its columns'
  // (midpoint rate x column step, the angle vectors summed: the same product where the rate holds over the
  // block, and within |a1||a2|/2 of it where a gyro sample's edge falls inside), one sine and cosine per block;
  // the columns inside a block take the matrices at its two ends interpolated linearly in time (off the
  // rotation by at most a^2/8 for a block turning by a: 3e-7 rad at 1 rad/s over 16 columns of an OS-1 at 10 Hz).
  size_t at = 0;  // the gyro sample of the last step
  const auto exp_map = [](const Eigen::Vector3d& th) {
    const double a = th.norm();
    return a > 0 ? Eigen::Matrix3d(Eigen::AngleAxisd(a, th / a).toRotationMatrix()) : Eigen::Matrix3d::Identity();
  };
  // From column cm (rotation Rm) to column `end` in steps of `dir` (+1 forward in time, -1 backward).
  const auto walk = [&](const Eigen::Matrix3d& Rm, int end, int dir) {
    Eigen::Matrix3d Ra = Rm;
    int a = cm;  // the block's first column (its rotation known)
    // The block's angle vector, entry by entry (th += rate * dt as Eigen sums it), in registers; and the columns
    // stepped in this block (the block ends at kDeskewBlockCols).
    double th0 = 0, th1 = 0, th2 = 0;
    int in_block = 0;
    for (int c = cm + dir; dir > 0 ? c <= end : c >= end; c += dir) {
      const int64_t ta = col_t_[c - dir], tb = col_t_[c];
      const Eigen::Vector3d& w = sweep_rate_walk(ta + (tb - ta) / 2, at);
      const double dt = 1e-6 * double(tb - ta);
      th0 += w[0] * dt;
      th1 += w[1] * dt;
      th2 += w[2] * dt;
      if (++in_block != kDeskewBlockCols && c != end) continue;
      in_block = 0;
      const Eigen::Matrix3d Rb = Ra * exp_map(Eigen::Vector3d(th0, th1, th2));
      const Eigen::Matrix3f fa = Ra.cast<float>(), fb = Rb.cast<float>();
      put(c, fb);
      const Eigen::Matrix3f diff = fb - fa;
      const int64_t span = col_t_[c] - col_t_[a];
      const double per_us = span != 0 ? 1.0 / double(span) : 0.0;
      float fa9[9], d9[9];  // (entry e = (e / 3, e % 3))
      for (int e = 0; e < 9; ++e) {
        fa9[e] = fa(e / 3, e % 3);
        d9[e] = diff(e / 3, e % 3);
      }
      for (int i = a + dir; i != c; i += dir) {  // fa + s diff, entry by entry
        const float s = float(double(col_t_[i] - col_t_[a]) * per_us);
        float* g = at_col(i);
#pragma GCC unroll 9
        for (int e = 0; e < 9; ++e) g[e * 8] = fa9[e] + s * d9[e];
      }
      Ra = Rb;
      a = c;
      th0 = th1 = th2 = 0;
    }
  };
  const Eigen::Matrix3d Rm = exp_map(sweep_rate_walk(tm + (col_t_[cm] - tm) / 2, at) * (1e-6 * double(col_t_[cm] - tm)));
  put(cm, Rm.cast<float>());
  const size_t at_m = at;
  walk(Rm, W - 1, +1);
  at = at_m;
  walk(Rm, 0, -1);
  return true;
}

}  // namespace fploc::seg
