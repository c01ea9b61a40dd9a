// The ground at a kink (a ramp's foot or head): which returns go into the ground plane.
//
// Near a ramp's foot or head the lower rings see two surfaces: the ramp and the level floor or landing beside,
// behind or ahead of it. The ring fit then settles on a compromise over both (a plane that is neither, tilted
// by a fraction of the ramp's slope and moving in steps the gyro does not see), and its distance is the
// sensor's height above no surface at all. The lowest ring of an OS-1 at 1.2 m reaches the floor only ~4 m
// out, so the patch "under the robot" cannot be fitted on its own; what separates the two surfaces is where
// they are seen: the ramp in some azimuth sectors, the floor or landing in others.
//
// So (with a gyro; without one the ring fit stays as it is): the returns near the fitted plane are split into
// cells (azimuth sector x horizontal-distance band, "sectors" below), each fits its own plane (Tukey IRLS from
// the ring fit's plane, the cut-off shrinking). Then:
//  - F, the sectors on the surface followed since the last scans (the last F's normal carried by the gyro);
//    when it has left the view (past a ramp's head), the surface of the largest sector if others agree;
//    O, the sectors kinked against F by more than kKinkDeg (and 3 sigmas);
//  - the height (Plane::under_m) is the distance to the surface under the robot: of F and O, the one on the
//    sensor's side of the line where the two planes meet (each group's sectors all on one side of it); F
//    when that is unclear or O is missing;
//  - F's plane is fitted again from its own returns (Tukey, the cut-off shrinking to 2 cm): a sector the kink
//    line passes through is a compromise that still counts as F, its returns on the other surface do not;
//  - where the ground gives the attitude (no ceiling, or one that disagrees with the ring fit), F's plane
//    replaces the ring fit, so that GravityFusion sees one surface (its own rotation) or a clean step to
//    another, never a compromise sliding between them (nor the ring fit's pull towards a ramp, a hole or
//    clutter beside the floor). Where the ceiling gives the attitude (the paper's sequences) the ring fit
//    stays when F is on it.
// Said in status_text. Transport-free, part of Segmenter::process.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "fploc/segmentation/segmenter.h"
#include "plane_kernels.h"
#include "plane_math.h"
#include "kink_cells.h"
#include "segmenter_constants.h"

namespace fploc::seg {

namespace {
using kink::kSectorBandM;
constexpr int kSectors = kink::kCells;    // the cells of kink_cells.h ("sectors" below)
constexpr float kSectorTightM = 0.05f;    // at the end, returns this near the sector's own plane (kSectorBandM: near the ring fit's)
constexpr int kMinSectorPoints = 40;      // a sector with fewer returns says nothing
constexpr double kSectorMaxRmsM = 0.02;   // a sector's rms about its plane (one surface)
constexpr double kKinkDeg = 3.0;          // another surface: this far from the followed one
constexpr double kSideShare = 0.9;        // of a group's returns on one side of the kink line
constexpr double kFollowDeg = 1.5;        // a sector this near a surface is on it
constexpr std::array<float, 3> kRefineCutM{0.05f, 0.03f, 0.02f};  // the followed surface's own fit (Tukey cut-offs)
// One surface followed steadily (SegmenterConfig::kink_recheck_scans): the split is skipped while the ring fit
// stays within kQuietOffDeg of the surface the last split followed (carried by the gyro; half the kKinkFitOffDeg
// at which the split replaces the ring fit) and within kQuietStepM of its distance (a step to another surface).
constexpr double kQuietOffDeg = 0.5 * k::kKinkFitOffDeg;
constexpr double kQuietStepM = 0.01;
constexpr int64_t kFollowRateMaxDtUs = 300'000;  // consecutive distances at most this far apart for the rate
constexpr double kQuietRefRateMs = 0.1;          // the rate at which the sweep's tilt per unit rate is measured

constexpr int32_t kPad = 8;              // the kernels' lanes

// Moments of the points (relative to ref; np a multiple of kPad, the padding far off the plane) within c of
// the plane pl (sensor frame): Tukey-weighted ((1 - (r/c)^2)^2), or each weighing 1 (unweighted).
detail::Moments moments_near(const float* x, const float* y, const float* z, size_t np, const Eigen::Vector4d& pl,
                             const Eigen::Vector3d& ref, float c, bool unweighted) {
  const kern::PlaneF plf{float(pl[0]), float(pl[1]), float(pl[2]), float(pl.head<3>().dot(ref) + pl[3])};
  if (unweighted) {
    double S[9], r2 = 0;
    int count = 0, beyond = 0;
    const float zero[3] = {0.f, 0.f, 0.f};
    kern::inlier_moments(x, y, z, np, plf, c, std::numeric_limits<float>::infinity(), zero, S, r2, count, beyond);
    return detail::Moments::from_inliers(S, count);
  }
  double S[10];
  kern::tukey_moments(x, y, z, np, plf, 1.f / (c * c), S);
  return detail::Moments::from_weighted(S);
}

struct Group {
  detail::Moments m;
  Eigen::Vector4d pl = Eigen::Vector4d::Zero();
  int sectors = 0;
  std::array<bool, kSectors> member{};  // the sectors pooled
};
}  // namespace

void Segmenter::FollowRate::update(int64_t t, double d_now, bool same_surface) {
  if (same_surface && d_t != 0 && t > d_t && t - d_t < kFollowRateMaxDtUs) {
    const double dt = 1e-6 * double(t - d_t);
    const double raw = (d_now - d) / dt;
    if (std::abs(raw) > k::kFollowRateMaxMs) {
      ok = false;
    } else if (ok) {
      // Exponentially weighted mean and variance of the raw rates (each scan's distance is a few millimetres off:
      // more where the surface is seen only far away).
      gain = 1 - std::exp(-dt / k::kFollowRateTauS);
      const double e = raw - rate;
      rate += gain * e;
      var = (1 - gain) * (var + gain * e * e);
    } else {
      rate = raw;
      var = raw * raw;  // nothing known of its spread yet
      gain = 1;
      ok = true;
    }
  } else {
    ok = false;
  }
  d = d_now;
  d_t = t;
}

bool Segmenter::FollowRate::stands_out() const {
  // Only a rate that stands out of its own noise (2 sigmas of the weighted mean): a wrong one would skew the fit.
  const double sigma = std::sqrt(var * gain / (2 - gain));
  return ok && std::abs(rate) > 2 * sigma;
}

void Segmenter::split_ground_at_kink(int64_t t, const Scan& scan) {
  Plane& g = out_.ground;
  g.under_m = 0;
  // The followed surface is carried from scan to scan by the gyro: without one, the ring fit as it is.
  if (!cfg_.imu_attitude || !fusion_.has_gyro()) return;
  if (!g.found || lower_.n < 100) {  // (the followed surface is kept for up to 1 s)
    kink_quiet_left_ = 0;
    kink_armed_ = false;
    return;
  }
  const Eigen::Vector3d up = g.coeffs.head<3>();  // the ground's normal points up (into the room)
  const auto angle = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    return std::acos(std::clamp(u.dot(v), -1.0, 1.0));
  };
  // The ground to follow: the last scan's, carried by the gyro.
  Eigen::Vector3d prev = up;
  Eigen::Matrix3d R;
  const bool carried =
      follow_t_ != 0 && t - follow_t_ < 1'000'000 && fusion_.rotation(follow_t_, t, deskew_.bias(), &R);
  if (carried) prev = (R.transpose() * follow_up_).normalized();
  const bool ground_attitude =
      !out_.ceiling.found ||
      angle(-out_.ceiling.coeffs.head<3>(), up) > cfg_.attitude_consistency_deg * k::kDeg;
  // One surface followed steadily: the last split found it alone with the ring fit on it and the ceiling giving
  // the attitude (its result: the ring fit as it is), and this scan's ring fit is still on it, at its distance,
  // the ceiling still giving the attitude and no sweep's translation to correct. The split would give the ring
  // fit again; it is skipped (at most kink_recheck_scans - 1 scans in a row), the surface carried by the gyro
  // and its distance, the ring fit's plus the difference of the two at the last split (they differ by a few
  // millimetres: the surface's own fit has fewer returns and a tighter cut-off), kept for the rate.
  const double d_followed = g.coeffs[3] + kink_d_offset_;
  // A recheck: a scan that would be skipped but for the count (kink_recheck_scans) running out.
  bool recheck = false;
  if (carried && t - follow_t_ < kFollowRateMaxDtUs && !ground_attitude &&
      angle(up, prev) < kQuietOffDeg * k::kDeg && std::abs(d_followed - follow_.d) < kQuietStepM) {
    FollowRate next = follow_;
    next.update(t, d_followed, true);
    // The sweep's translation: its rate too low to be corrected, or the tilt it would correct (the last split's
    // measured tilt per unit rate, the same returns seen) within half of kSweepSkewDeg.
    if (!next.stands_out() || kink_skew_per_rate_ * std::abs(next.rate) < 0.5 * k::kSweepSkewDeg * k::kDeg) {
      if (kink_quiet_left_ > 0) {
        follow_ = next;
        follow_up_ = prev;
        follow_t_ = t;
        --kink_quiet_left_;
        ++kink_skipped_;
        return;
      }
      recheck = kink_armed_;
    }
  }
  kink_quiet_left_ = 0;
  kink_armed_ = false;
  // A recheck runs on every kink_recheck_stride-th of the returns near the ring fit (SegmenterConfig): kept when
  // it finds the one surface again (the ring fit on it, nothing to correct: the scan's planes as they are, the
  // skipping re-armed), else undone and the split run on all of them, which decides every other outcome.
  const int stride = std::max(cfg_.kink_recheck_stride, 1);
  if (recheck && stride > 1) {
    const FollowRate follow0 = follow_;
    const Eigen::Vector3d up0 = follow_up_;
    const int64_t t0 = follow_t_;
    const double skew0 = kink_skew_per_rate_, offset0 = kink_d_offset_;
    const Plane g0 = g;
    const size_t text0 = out_.status_text.size();
    if (split_ground(t, scan, up, prev, ground_attitude, stride)) {
      ++kink_thinned_;
      return;
    }
    follow_ = follow0;
    follow_up_ = up0;
    follow_t_ = t0;
    kink_skew_per_rate_ = skew0;
    kink_d_offset_ = offset0;
    kink_quiet_left_ = 0;
    kink_armed_ = false;
    g = g0;
    out_.status_text.resize(text0);
  }
  split_ground(t, scan, up, prev, ground_attitude, 1);
}

bool Segmenter::split_ground(int64_t t, const Scan& scan, const Eigen::Vector3d& up, Eigen::Vector3d prev,
                             bool ground_attitude, int stride) {
  Plane& g = out_.ground;
  const auto angle = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    return std::acos(std::clamp(u.dot(v), -1.0, 1.0));
  };
  // (a thinned recheck's counts: its sectors' returns are 1 / stride of theirs)
  const double min_points = double(kMinSectorPoints) / stride;
  const Eigen::Vector3f n0 = g.coeffs.head<3>().cast<float>();
  const float d0 = float(g.coeffs[3]);
  const Eigen::Vector3d ref = -g.coeffs[3] * up;  // numerics: moments relative to the point under the sensor
  const Eigen::Vector3f reff = ref.cast<float>();
  // Per sector: three least-squares passes (a wide band around the ring fit, then tight around its own plane).
  std::array<Eigen::Vector4d, kSectors> spl;
  std::array<detail::Moments, kSectors> sm;
  std::array<bool, kSectors> ok{};
  std::array<double, kSectors> ssig{};  // the sector normal's 1-sigma [rad]
  // The returns near the ring fit's plane: their indices and sectors (kink_cells.h), in order.
  std::array<int32_t, kSectors> count{};  // returns per sector
  kink_index_.resize(((lower_.n + 7) & ~size_t(7)) + 8);
  kink_sector_.resize(kink_index_.size());
  size_t near = kink::cells(lower_.x.data(), lower_.y.data(), lower_.z.data(), lower_.n, n0, d0,
                            kink_index_.data(), kink_sector_.data(), count);
  if (stride > 1) {  // every stride-th return, in order
    int32_t* ix = kink_index_.data();
    int16_t* sc = kink_sector_.data();
    count.fill(0);
    size_t m = 0;
    for (size_t k = 0; k < near; k += size_t(stride), ++m) {
      ix[m] = ix[k];
      sc[m] = sc[k];
      ++count[size_t(sc[m])];
    }
    near = m;
  }
  const int32_t* index = kink_index_.data();
  const int16_t* sector = kink_sector_.data();
  // The points grouped by sector (relative to ref), each sector's block padded to a multiple of kPad with a
  // point 1 km above the ground (outside every cut-off), for the vectorised moments (plane_kernels.h).
  std::array<int32_t, kSectors + 1> block;  // sector s's padded block: [block[s], block[s + 1])
  block[0] = 0;
  for (int s = 0; s < kSectors; ++s) block[size_t(s) + 1] = block[size_t(s)] + (count[size_t(s)] + kPad - 1) / kPad * kPad;
  const size_t padded = size_t(block[kSectors]);
  const Eigen::Vector3f pad_point = 1e3f * n0;  // 1 km above the ground
  kink_x_.resize(padded);
  kink_y_.resize(padded);
  kink_z_.resize(padded);
  for (int s = 0; s < kSectors; ++s)
    for (size_t o = size_t(block[size_t(s)] + count[size_t(s)]); o < size_t(block[size_t(s) + 1]); ++o) {
      kink_x_[o] = pad_point.x();
      kink_y_[o] = pad_point.y();
      kink_z_[o] = pad_point.z();
    }
  {
    // (a ring's returns come sector after sector: the slot is kept in a register along a run of one sector)
    std::array<int32_t, kSectors> at;
    std::copy(block.begin(), block.begin() + kSectors, at.begin());
    int16_t cur = near > 0 ? sector[0] : 0;
    size_t o = near > 0 ? size_t(at[size_t(cur)]) : 0;
    for (size_t k = 0; k < near; ++k) {
      if (sector[k] != cur) {
        at[size_t(cur)] = int32_t(o);
        cur = sector[k];
        o = size_t(at[size_t(cur)]);
      }
      const size_t i = size_t(index[k]);
      kink_x_[o] = lower_.x[i] - reff.x();
      kink_y_[o] = lower_.y[i] - reff.y();
      kink_z_[o] = lower_.z[i] - reff.z();
      ++o;
    }
  }
  for (int s = 0; s < kSectors; ++s) spl[s] = g.coeffs;
  // Tukey IRLS per sector from the ring fit's plane, the cut-off shrinking (a wall's foot, clutter on the
  // floor drop out; a surface kinked against the ring fit's compromise is followed); the last pass: every
  // return within kSectorTightM, unweighted.
  constexpr std::array<float, 4> kCut{0.3f, 0.15f, 0.08f, 0.05f};
  for (size_t pass = 0; pass <= kCut.size(); ++pass) {
    const bool last = pass == kCut.size();
    const float c = last ? kSectorTightM : kCut[pass];
    for (int s = 0; s < kSectors; ++s) {
      const size_t b = size_t(block[size_t(s)]), np = size_t(block[size_t(s) + 1]) - b;
      sm[s] = np == 0 ? detail::Moments{} : moments_near(kink_x_.data() + b, kink_y_.data() + b, kink_z_.data() + b, np, spl[s], ref, c, last);
    }
    for (int s = 0; s < kSectors; ++s) {
      Eigen::Vector3d ev;
      ok[s] = sm[s].w >= (last ? min_points : 0.25 * min_points) && sm[s].plane(ref, -up, spl[s], &ev);
      if (ok[s] && last) {
        // One surface: a sector seeing only a strip (one ring's arc, a wall's foot) has no second in-plane
        // direction; its rms must be that of one surface.
        const double rms = std::sqrt(std::max(ev[0], 0.0) / sm[s].w);
        ok[s] = ev[1] > 0.05 * sm[s].w && rms < kSectorMaxRmsM &&
                std::acos(std::clamp(spl[s].head<3>().dot(up), -1.0, 1.0)) < k::kMaxGroundTiltDeg * k::kDeg * 3;
        ssig[s] = std::max(rms, 1e-3) / std::sqrt(std::max(ev[1], 1e-9));
      }
      if (!ok[s]) spl[s] = g.coeffs;
    }
  }
  // Until a surface is found below: the ring fit's.
  follow_up_ = up;
  follow_t_ = t;
  // F: the sectors on that surface; O: those on another one (kinked against F's plane by more than kKinkDeg).
  Group F, O;
  // The sectors within kFollowDeg of a surface's normal, pooled.
  const auto gather = [&](const Eigen::Vector3d& normal, Group& grp) {
    grp = Group{};
    for (int s = 0; s < kSectors; ++s) {
      grp.member[s] = ok[s] && angle(spl[s].head<3>(), normal) < kFollowDeg * k::kDeg;
      if (!grp.member[s]) continue;
      grp.m.w += sm[s].w;
      grp.m.s += sm[s].s;
      grp.m.ss += sm[s].ss;
      ++grp.sectors;
    }
  };
  gather(prev, F);
  bool same_surface = true;  // F is the surface followed in the last scan
  if (F.sectors < 2 || F.m.w < 4 * min_points) {
    // The surface seen before has left the view (past a ramp's head): the surface of the largest sector, if
    // others agree with it.
    same_surface = false;
    int big = -1;
    for (int s = 0; s < kSectors; ++s)
      if (ok[s] && (big < 0 || sm[s].w > sm[big].w)) big = s;
    F = Group{};
    if (big >= 0) {
      prev = spl[big].head<3>();
      gather(prev, F);
    }
  }
  if (F.sectors < 2 || F.m.w < 4 * min_points || !F.m.plane(ref, -up, F.pl)) {
    follow_.ok = false;
    return false;  // the ring fit as it is
  }
  // F's plane from its returns, each weighed by its distance to that plane (Tukey, the cut-off shrinking). A
  // sector the kink line passes through (the level floor and the ramp's first metre behind the robot, the
  // landing and the ramp's last metre ahead of it) fits a compromise between the two surfaces that can still be
  // within kFollowDeg of the followed one: pooled as it is, it tilts F by a few tenths of a degree. Its returns
  // on the other surface lie centimetres off F's plane and drop out here.
  const std::array<bool, kSectors>& in_f = F.member;
  {
    // F's returns within the first cut-off of its pooled plane (relative to ref), padded as the sectors' blocks.
    const Eigen::Vector3f n0f = F.pl.head<3>().cast<float>();
    const float d0f = float(F.pl[3]) + n0f.dot(reff);
    size_t room = kPad;  // (the kernel writes up to 7 slots past its count)
    for (int s = 0; s < kSectors; ++s)
      if (in_f[s]) room += size_t(count[size_t(s)]);
    for (auto* v : {&near_x_, &near_y_, &near_z_}) v->resize(room + kPad);
    size_t m = 0;
    for (int s = 0; s < kSectors; ++s) {
      if (!in_f[s]) continue;
      const size_t b = size_t(block[size_t(s)]);
      m = kink::near_plane(kink_x_.data() + b, kink_y_.data() + b, kink_z_.data() + b, size_t(count[size_t(s)]), n0f,
                           d0f, kRefineCutM[0], near_x_.data(), near_y_.data(), near_z_.data(), m);
    }
    for (; m % kPad; ++m) {
      near_x_[m] = pad_point.x();
      near_y_[m] = pad_point.y();
      near_z_[m] = pad_point.z();
    }
    for (auto* v : {&near_x_, &near_y_, &near_z_}) v->resize(m);
    Eigen::Vector4d pl = F.pl;
    for (const float c : kRefineCutM) {
      const detail::Moments m = moments_near(near_x_.data(), near_y_.data(), near_z_.data(), near_x_.size(), pl, ref, c, false);
      if (m.w < 2 * min_points || !m.plane(ref, -up, pl)) break;
      F.pl = pl;
    }
  }
  // The sweep's translation. The gyro de-skews rotation only: a return measured tau seconds from the planes'
  // time lies off the surface by the sensor's speed off it (the rate of the surface's distance) x tau. For a
  // surface the sensor moves parallel to (a floor from the floor, a ramp from the ramp) that is nothing; for the
  // level floor seen from a ramp (12 cm/s at 0.9 m/s on a 7 deg ramp) the sweep's first and last columns, both
  // behind the sensor, differ by a centimetre, and where the floor is seen only there (behind, the ramp ahead
  // and the walls beside) its fit is rolled by a few tenths of a degree. The rate is the change of the
  // followed surface's distance from scan to scan (low-passed); the returns moved back by rate x tau along
  // the surface's normal and the surface fitted again. Used only where it tilts the fit by more than a plane
  // fit's own noise (kSweepSkewDeg): a robot driving on the surface it sees is left as it is.
  follow_.update(t, F.pl[3], same_surface);
  // A plane corrected for the sweep's translation: its returns (those `use` takes, within kSectorTightM of it)
  // fitted as measured and moved back by rate x tau, the difference of the two fits added to it (the plane
  // keeps its own fit's weighting; only the skew is removed). rate: the sensor's speed off the surface [m/s].
  // Returns the tilt removed [rad] (0: not possible).
  const int W = scan.width;
  const bool has_times = W > 0 && int(scan.column_utime.size()) == W && lower_.width == W;
  const bool can_deskew = follow_.stands_out() && has_times;
  const bool pow2 = W > 0 && (W & (W - 1)) == 0;  // (the column of a pixel by a mask, not a division)
  const auto sweep_corrected = [&](const Eigen::Vector4d& pl, auto&& use, double rate, Eigen::Vector4d* out) {
    const Eigen::Vector3f n = pl.head<3>().cast<float>();
    const Eigen::Vector3f shift = float(rate) * n;
    // The returns taken, relative to ref as measured (a) and moved back (b), in float, in order; then their
    // moments (Moments::of_points: the sums of adding them one at a time, kept in registers).
    sweep_q_.resize(6 * near);
    float *ax = sweep_q_.data(), *ay = ax + near, *az = ay + near, *bx = az + near, *by = bx + near, *bz = by + near;
    size_t m = 0;
    for (size_t k = 0; k < near; ++k) {  // (a return within kSectorTightM of pl is one near the ring fit)
      if (!use(sector[k])) continue;
      const size_t i = size_t(index[k]);
      const int64_t tc = scan.column_utime[size_t(pow2 ? lower_.pixel[i] & (W - 1) : lower_.pixel[i] % W)];
      const Eigen::Vector3f p = lower_.point(i);
      if (tc == 0 || !p.allFinite() || std::abs(n.dot(p) + float(pl[3])) >= kSectorTightM) continue;
      const Eigen::Vector3f a = p - reff;
      const Eigen::Vector3f b = p + float(1e-6 * double(tc - t)) * shift - reff;
      ax[m] = a.x();
      ay[m] = a.y();
      az[m] = a.z();
      bx[m] = b.x();
      by[m] = b.y();
      bz[m] = b.z();
      ++m;
    }
    const detail::Moments m0 = detail::Moments::of_points(ax, ay, az, m), m1 = detail::Moments::of_points(bx, by, bz, m);
    Eigen::Vector4d p0, p1;
    if (m0.w < 4 * min_points || !m0.plane(ref, -up, p0) || !m1.plane(ref, -up, p1)) return 0.0;
    const Eigen::Vector3d nc = (pl.head<3>() + p1.head<3>() - p0.head<3>()).normalized();
    *out = Eigen::Vector4d(nc.x(), nc.y(), nc.z(), pl[3] + p1[3] - p0[3]);
    return angle(nc, pl.head<3>());
  };
  bool sweep_deskewed = false;
  double sweep_skew = 0;
  if (can_deskew) {
    Eigen::Vector4d Fc;
    sweep_skew = sweep_corrected(F.pl, [&](int16_t s) {
      return in_f[size_t(s)];
    }, follow_.rate, &Fc);
    if (sweep_skew > k::kSweepSkewDeg * k::kDeg) {
      F.pl = Fc;
      sweep_deskewed = true;
    }
  }
  follow_up_ = F.pl.head<3>();
  int seed = -1;
  double far = kKinkDeg * k::kDeg;
  for (int s = 0; s < kSectors; ++s)
    if (ok[s] && angle(spl[s].head<3>(), F.pl.head<3>()) > std::max(far, 3 * ssig[s])) far = angle(spl[s].head<3>(), F.pl.head<3>()), seed = s;
  if (seed >= 0) {
    gather(spl[seed].head<3>(), O);
    if (O.m.w < 4 * min_points || !O.m.plane(ref, -up, O.pl)) O.sectors = 0;
  }
  const double off_fit = angle(F.pl.head<3>(), up);
  if (O.sectors == 0 && off_fit < k::kKinkFitOffDeg * k::kDeg && !ground_attitude) {
    // One surface, the ring fit on it, and the ceiling gives the attitude: the ring fit corrected for the sweep's
    // translation as the followed surface was. (Where the ground gives the attitude, F's own fit replaces the ring
    // fit below: on the demo building's first floor the ring fit was 0.1-0.3 deg off where F was within 0.03.)
    Eigen::Vector4d gc;
    const double skew = sweep_deskewed ? sweep_corrected(g.coeffs, [](int16_t) { return true; }, follow_.rate, &gc) : 0.0;
    // The ring fit as it is, well within the kink's threshold of the followed surface: the next scans may skip
    // the split while that holds (see the top).
    const bool quiet = !sweep_deskewed && off_fit < kQuietOffDeg * k::kDeg;
    if (quiet) {
      kink_quiet_left_ = std::max(cfg_.kink_recheck_scans, 1) - 1;
      kink_armed_ = true;
      // The tilt the sweep's translation gives the followed surface's fit per unit of rate (as measured, or at
      // kQuietRefRateMs: linear for the millimetres to centimetres involved), for the skipped scans' rates.
      Eigen::Vector4d unused;
      kink_skew_per_rate_ = can_deskew && follow_.rate != 0 ? sweep_skew / std::abs(follow_.rate)
                            : has_times ? sweep_corrected(F.pl, [&](int16_t s) { return in_f[size_t(s)]; }, kQuietRefRateMs, &unused) / kQuietRefRateMs
                                        : 0.0;
      kink_d_offset_ = F.pl[3] - g.coeffs[3];
    }
    if (skew > k::kSweepSkewDeg * k::kDeg) {
      g.coeffs = gc;
      char buf[200];
      std::snprintf(buf, sizeof buf, "ground: the sensor moving %.3f m/s off it, de-skewed for the sweep's translation (%.2f deg)",
                    follow_.rate, skew / k::kDeg);
      out_.note(buf);
    }
    return quiet;  // (quiet: no sweep correction, the planes as they are)
  }
  // The surface under the robot: the one on the sensor's side of the line where the two planes meet. Each
  // group's sectors lie on one side of that line (the other plane is below them: its height of them has one
  // sign, for nearly all of their returns); at the sensor the same sign of (height above the other - height
  // above this one) puts the sensor over this one. A group seen all around the robot (the line passes near
  // it, or the "other surface" is a patch inside it) has no side: the followed surface.
  int under = 0;  // 0: F, 1: O, -1: unclear
  if (O.sectors > 0) {
    const auto side = [&](const Group& A, const Group& B) {  // +1/-1: A's sectors all on one side; 0: mixed
      double pos = 0, neg = 0;
      for (int s = 0; s < kSectors; ++s) {
        if (!ok[s] || sm[s].w <= 0) continue;
        if (!A.member[s]) continue;
        const Eigen::Vector3d c = sm[s].s / sm[s].w + ref;
        (B.pl.head<3>().dot(c) + B.pl[3] > 0 ? pos : neg) += sm[s].w;
      }
      return pos >= kSideShare * (pos + neg) ? 1 : neg >= kSideShare * (pos + neg) ? -1 : 0;
    };
    const int sf = side(F, O), so = side(O, F);
    const double at_sensor = O.pl[3] - F.pl[3];  // height above O - height above F, at the sensor
    if (sf != 0 && so != 0) under = sf * at_sensor > 0 ? 0 : so * -at_sensor > 0 ? 1 : -1;
    else under = -1;
  }
  Plane followed = g;
  followed.coeffs = F.pl;
  quality(lower_, followed);
  if (followed.inliers < scale_.min_plane_inliers) return false;  // too little of it: the ring fit as it is
  // The height is the distance to the surface under the robot. Where the ground gives the attitude (no
  // ceiling, or one that disagrees with the ring fit: AttitudeHeight then takes the ground), the followed
  // surface replaces the ring fit, so that GravityFusion sees one surface (its own rotation) or a clean step
  // to another, never a compromise sliding between them. Where the ceiling agrees with the ring fit, the ring
  // fit stays (tried: always F; at a ramp's foot F is the level floor beside the ramp while the ceiling follows
  // the ramp, the attitude source toggled between them and the slope estimate lost 1 deg).
  if (ground_attitude) {
    const double under_d = under == 1 ? O.pl[3] : 0.0;
    g = followed;
    g.found = true;
    g.under_m = under_d;
  } else {
    g.under_m = under == 1 ? O.pl[3] : F.pl[3];
  }
  const double kink = O.sectors > 0 ? angle(F.pl.head<3>(), O.pl.head<3>()) : 0.0;
  char buf[240];
  if (O.sectors > 0)
    std::snprintf(buf, sizeof buf,
                  "ground: two surfaces %.2f deg apart (sectors %d / %d; the one seen before %.2f deg off the ring fit): "
                  "height above %s",
                  kink / k::kDeg, F.sectors, O.sectors, off_fit / k::kDeg,
                  under < 0 ? "it (which is under the robot unclear)" : under == 0 ? "it (under the robot)" : "the other (under the robot)");
  else
    std::snprintf(buf, sizeof buf, "ground: the ring fit %.2f deg off the surface seen before (%d sectors): height above that surface", off_fit / k::kDeg,
                  F.sectors);
  out_.note(buf);
  if (sweep_deskewed) {
    std::snprintf(buf, sizeof buf, " (the sensor moving %.3f m/s off it: de-skewed for the sweep's translation, %.2f deg)",
                  follow_.rate, sweep_skew / k::kDeg);
    out_.status_text += buf;
  }
  return false;
}

}  // namespace fploc::seg
