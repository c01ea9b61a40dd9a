// The paper's ring-based robust plane fit (section IV-A): max-range seeds on the K_r outermost rings,
// trimmed linear regression, the best-supported start, IRLS with a Tukey biweight.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "fploc/segmentation/plane_fit.h"
#include "compact_kernels.h"
#include "plane_kernels.h"
#include "plane_math.h"
#include "seed_order.h"
#include "segmenter_constants.h"
#include "simd4.h"

namespace fploc::seg {

using detail::basis;
using detail::max0;
using detail::median_inplace;
using detail::Moments;

void RingPlaneFit::pick_seeds(const Candidates& c, const Eigen::Vector3f& upf) {
  // On each of the K_r outermost rings, the largest-range point of every azimuth sector, keeping the
  // largest fraction of those (obstructed rays are shorter), and only points above the sensor.
  const int S = std::max(k::kMinSectors, cfg_.seed_sectors);
  seeds_.clear();
  all_seeds_.clear();
  const int kr = std::min(std::max(1, c.seed_rings > 0 ? c.seed_rings : cfg_.seed_rings), c.rings());
  if (int(sector_of_col_.size()) != c.width || sector_cols_s_ != S) {  // col * S / width, once per sensor
    sector_of_col_.resize(size_t(std::max(0, c.width)));
    for (int col = 0; col < c.width; ++col) sector_of_col_[size_t(col)] = col * S / c.width;
    sector_cols_s_ = S;
  }
  for (int r = 0; r < kr; ++r) {
    sector_best_.assign(S, -1.f);
    sector_idx_.assign(S, -1);
    // A ring is one scan row: its column is the pixel index minus the row's first pixel (no division per point).
    const int row0 = c.ring_start[r] < c.ring_start[r + 1] ? c.pixel[c.ring_start[r]] / c.width * c.width : 0;
    // The ring is in column order, so a sector's points are one run: its maximum is kept in registers
    // (the first of equal ranges, as a strict > over the points in order) and stored when the sector changes.
    // A point below the seed height counts as range -inf (never above the -1 start).
    // The seed ranges first, four points at a time (the height summed as Eigen's dot, x + (y + z)).
    const int rs = c.ring_start[r], re = c.ring_start[r + 1];
    seed_rv_.resize(size_t(std::max(0, re - rs)));
    {
      using namespace simd;
      const float* px = c.x.data();
      const float* py = c.y.data();
      const float* pz = c.z.data();
      const float* prange = c.range.data();
      const v4f ux = splat(upf.x()), uy = splat(upf.y()), uz = splat(upf.z()), hmin = splat(k::kMinSeedHeightM);
      const v4f ninf = splat(-std::numeric_limits<float>::infinity());
      float* rv = seed_rv_.data() - rs;
      int i = rs;
      for (; i + 4 <= re; i += 4) {
        const v4f h = ux * load(px + i) + (uy * load(py + i) + uz * load(pz + i));
        store(rv + i, h < hmin ? ninf : load(prange + i));
      }
      for (; i < re; ++i)
        rv[i] = upf.dot(Eigen::Vector3f(px[i], py[i], pz[i])) < k::kMinSeedHeightM ? -std::numeric_limits<float>::infinity()
                                                                                  : prange[i];
    }
    const float* prv = seed_rv_.data() - rs;
    const int32_t* ppix = c.pixel.data();
    const int* sec = sector_of_col_.data();
    int cur_s = -1, cur_i = -1;
    float cur_best = -1.f;
    for (int i = rs; i < re; ++i) {
      const int s = sec[ppix[i] - row0];
      if (s != cur_s) {
        if (cur_s >= 0) {
          sector_best_[size_t(cur_s)] = cur_best;
          sector_idx_[size_t(cur_s)] = cur_i;
        }
        cur_s = s;
        cur_best = sector_best_[size_t(s)];
        cur_i = sector_idx_[size_t(s)];
      }
      const float rv = prv[i];
      const bool better = rv > cur_best;
      cur_i = better ? i : cur_i;
      cur_best = better ? rv : cur_best;
    }
    if (cur_s >= 0) {
      sector_best_[size_t(cur_s)] = cur_best;
      sector_idx_[size_t(cur_s)] = cur_i;
    }
    // The sector maxima by range, largest first (seed_order.h: the order of the indices sorted by c.range).
    seed_keys_.clear();
    for (int s = 0; s < S; ++s)
      if (sector_idx_[s] >= 0) seed_keys_.push_back({c.range[size_t(sector_idx_[s])], sector_idx_[s]});
    seeds::sort_by_range(seed_keys_);
    const size_t keep = std::min(seed_keys_.size(), std::max<size_t>(k::kMinSeedsKept, size_t(std::ceil(cfg_.seed_fraction * S))));
    for (size_t j = 0; j < seed_keys_.size(); ++j) {
      if (j < keep) seeds_.push_back(seed_keys_[j].index);
      all_seeds_.push_back(seed_keys_[j].index);
    }
  }
}

// Support = soft inlier count (MSAC: 1 - (r/T)^2 for |r| < T) minus (1 / max_beyond_ratio) per return more
// than 2 inlier bands *beyond* the plane: a ceiling is where the rays end, so a plane cutting through
// walls (many "inliers" at one height in a corridor) loses, and a plane the acceptance test would reject
// (beyond > max_beyond_ratio x inliers) scores below zero. The soft count prefers the tight fit over a
// loose plane that merely stays within T of a narrow ceiling strip.
double RingPlaneFit::score_band(const PointsSoa& sub, size_t stride, const Eigen::Vector4d& pl, float band) const {
  const float beyond_thr = 2 * float(cfg_.inlier_threshold_m);
  const float beyond_weight = float(1.0 / std::max(k::kMinBeyondRatio, cfg_.max_beyond_ratio));
  // The NaN padding adds nothing.
  float soft = 0;
  int beyond = 0;
  kern::soft_score(sub.x.data(), sub.y.data(), sub.z.data(), sub.padded(),
                   {float(pl[0]), float(pl[1]), float(pl[2]), float(pl[3])}, 1.f / (band * band), -beyond_thr, soft, beyond);
  return double(soft - beyond_weight * float(beyond)) * double(stride);
}

// The start with the most support on a subsample of all half-ring points: the seed regression, last
// frame's plane, or planes through seed triplets (deterministic sampling). The triplets make the start
// robust when a tilted sensor's longest rays hit far walls, not the ceiling.
bool RingPlaneFit::choose_start(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous,
                                Eigen::Vector4d& cur) {
  Eigen::Vector3d e1, e2;
  basis(up, e1, e2);
  // Initial plane by linear regression h = a*x1 + b*x2 + g in the prior's frame, trimmed twice.
  bool have_seed_plane = false;
  Eigen::Vector4d seed_plane;
  std::vector<float> res;
  for (int round = 0; round < k::kSeedTrimRounds && seeds_.size() >= 3; ++round) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (int i : seeds_) {
      const Eigen::Vector3d p = c.point(size_t(i)).cast<double>();
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
    if (round == k::kSeedTrimRounds - 1) break;
    res.clear();
    for (int i : seeds_) res.push_back(std::abs(float(seed_plane.head<3>().dot(c.point(size_t(i)).cast<double>()) + seed_plane[3])));
    std::vector<float> tmp = res;
    const double thr = std::max(k::kSeedTrimMinM, k::kSeedTrimSigmas * k::kMadToSigma * median_inplace(tmp));
    std::vector<int> kept;
    for (size_t j = 0; j < seeds_.size(); ++j)
      if (res[j] <= thr) kept.push_back(seeds_[j]);
    if (kept.size() < 3 || kept.size() == seeds_.size()) break;
    seeds_.swap(kept);
  }

  const double max_tilt = cfg_.max_tilt_deg * k::kDeg;
  const float thr = float(cfg_.inlier_threshold_m);
  double best = -std::numeric_limits<double>::infinity();
  bool have_start = false;
  auto consider = [&](const Eigen::Vector4d& pl) {
    if (!pl.allFinite() || -pl.head<3>().dot(up) < std::cos(max_tilt) || pl[3] <= 0) return;
    const double sc = score_band(sub_start_, start_stride_, pl, thr);
    if (!have_start || sc > best) {
      best = sc;
      cur = pl;
      have_start = true;
    }
  };
  if (have_seed_plane) consider(seed_plane);
  if (previous) consider(*previous);
  uint32_t state = k::kTripletSeed;
  auto next = [&]() {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  for (int t = 0; t < cfg_.seed_triplets; ++t) {
    // Alternate between the longest-range seeds (the paper's) and all sector maxima (tilted sensor).
    const std::vector<int>& pool = (t % 2 == 0) ? seeds_ : all_seeds_;
    if (pool.size() < 3) continue;
    const Eigen::Vector3d a = c.point(size_t(pool[next() % pool.size()])).cast<double>();
    const Eigen::Vector3d b = c.point(size_t(pool[next() % pool.size()])).cast<double>();
    const Eigen::Vector3d q = c.point(size_t(pool[next() % pool.size()])).cast<double>();
    Eigen::Vector3d nn = (b - a).cross(q - a);
    if (nn.norm() < k::kMinTripletNormal) continue;
    nn.normalize();
    if (nn.dot(up) > 0) nn = -nn;
    Eigen::Vector4d pl;
    pl << nn, -nn.dot(a);
    consider(pl);
  }
  return have_start;
}

// M-estimator (IRLS, Tukey biweight) over all points of the half rings, cut-off shrinking from first_cut to
// ~4.7 robust sigmas of the inliers. The start already has its support within T = 5 cm, so the first
// cut-off only needs to cover its tilt error over the far ceiling (0.2 m); a wide one (0.5 m) lets the band
// of wall returns below a corridor ceiling (10x the ceiling returns there) dominate the first weighted fit,
// which then converges to a plane through the walls.
std::optional<RingPlaneFit::Fit> RingPlaneFit::refine(const Eigen::Vector3d& up, Eigen::Vector4d cur,
                                                      double first_cut, double min_cut, bool fixed,
                                                      const Fit* join) {
  using namespace simd;
  double last_sigma = 0;  // robust residual scale of the final iteration
  const Eigen::Vector3d ref = -cur[3] * cur.head<3>();  // a point of the plane (numerics)
  const Eigen::Vector3f reff = ref.cast<float>();
  double cut = first_cut;
  {
    // The band's points relative to ref, contiguous float arrays (streamed by every iteration); compacted
    // without a branch (about one point in five is in the band, a branch on it mispredicted often).
    const v4f nx = splat(float(cur[0])), ny = splat(float(cur[1])), nz = splat(float(cur[2])), d = splat(float(cur[3]));
    const v4f cb = splat(float(cut));
    band_.resize(np_ + 8);  // (+ 8: the eight-lane compaction writes up to 7 slots past the count)
    float *bx = band_.x.data(), *by = band_.y.data(), *bz = band_.z.data();
    size_t m = 0;
    const bool wide = ck::available() && kern::wide();
    if (wide) {
      const float plf[4] = {float(cur[0]), float(cur[1]), float(cur[2]), float(cur[3])};
      const float r3[3] = {reff.x(), reff.y(), reff.z()};
      const ck::BoxRange br(cand_->box.data(), cand_->box_stride, cand_->box_r, plf);
      m = ck::band(xs_, ys_, zs_, n_, np_, plf, float(cut), r3, bx, by, bz, cand_->has_boxes() ? &br : nullptr);
    }
    for (size_t i = 0; i < np_ && !wide; i += 4) {
      const v4f x = load(xs_ + i), y = load(ys_ + i), z = load(zs_ + i);
      const int in = movemask(abs(nx * x + ny * y + nz * z + d) < cb);  // NaN padding: false
      if (in == 0) continue;  // the band is a few contiguous runs per ring: mostly all or none of four
      const v4f qx = x - splat(reff.x()), qy = y - splat(reff.y()), qz = z - splat(reff.z());
      if (in == 15) {
        store(bx + m, qx);
        store(by + m, qy);
        store(bz + m, qz);
        m += 4;
        continue;
      }
      for (int l = 0; l < 4; ++l) {
        bx[m] = qx[l];
        by[m] = qy[l];
        bz[m] = qz[l];
        m += size_t((in >> l) & 1);
      }
    }
    // Padding: a point 1 km off the start plane (zero weight, outside every cut-off, finite).
    band_.resize(m);
    band_.pad(1e3f * float(cur[0]), 1e3f * float(cur[1]), 1e3f * float(cur[2]));
    // Every kShrinkSubsample-th band point (the subsample of the iterations whose cut-off still shrinks).
    band_sub_.resize((m + k::kShrinkSubsample - 1) / k::kShrinkSubsample);
    if (wide) ck::strided(bx, by, bz, band_sub_.n, k::kShrinkSubsample, band_sub_.x.data(), band_sub_.y.data(), band_sub_.z.data());
    for (size_t j = 0, o = 0; j < m && !wide; j += k::kShrinkSubsample, ++o) {
      band_sub_.x[o] = bx[j];
      band_sub_.y[o] = by[j];
      band_sub_.z[o] = bz[j];
    }
    band_sub_.pad(1e3f * float(cur[0]), 1e3f * float(cur[1]), 1e3f * float(cur[2]));
  }
  const size_t nb = band_.n;
  if (nb < 3) return std::nullopt;
  // While the cut-off still shrinks, the scale and the weighted fit use every kShrinkSubsample-th band point
  // (band_sub_); once it stops shrinking, every point (band_).
  bool shrinking = !fixed;
  // (A refinement whose cut-off shrinks; the fixed cut-off's refit has its own test below.)
  auto joins = [&]() {
    return !fixed && join && join->cut > 0 && cut <= k::kJoinCutRatio * join->cut &&
           (cur.head<3>() - join->pl.head<3>()).norm() < k::kJoinNormal && std::abs(cur[3] - join->pl[3]) < k::kJoinDistM;
  };
  auto joined_fit = [&]() {
    Fit f = *join;
    f.joined = true;
    return f;
  };
  for (int it = 0; it < std::max(1, cfg_.irls_iterations); ++it) {
    const PointsSoa* src = shrinking ? &band_sub_ : &band_;
    // Robust scale (1.4826 * median |r| inside the cut-off) from the median's bin of a 256-bin histogram of the
    // residuals inside the cut-off, found by bisection over vectorised counts (no per-point increments).
    // `a < cut` is compared in float against the smallest float >= cut, which is the same test for every
    // float a; the padding points (1 km off the plane) are outside.
    const kern::PlaneF plf{float(cur[0]), float(cur[1]), float(cur[2]), float(cur.head<3>().dot(ref) + cur[3])};
    const float inv_binf = float(k::kScaleBins / cut);
    float cutf = float(cut);
    if (double(cutf) < cut) cutf = std::nextafter(cutf, std::numeric_limits<float>::infinity());
    // (grown, never shrunk: the iterations alternate between the subsample and the band, and residual_scale
    // writes every entry it reads; a resize up would zero-fill the difference each time)
    if (scratch_.size() < src->padded()) scratch_.resize(src->padded());
    int inside = 0;
    // The last iteration's scale as the guess of the bin (the result does not depend on it).
    const int hint = last_sigma > 0 ? int(std::min(double(k::kScaleBins), last_sigma / k::kMadToSigma * inv_binf)) : -1;
    const int bin = kern::residual_scale(src->x.data(), src->y.data(), src->z.data(), src->padded(), plf, inv_binf, cutf,
                                         scratch_.data(), inside, hint);
    if (inside < 3) return std::nullopt;
    const double sigma = k::kMadToSigma * (bin + 0.5) / inv_binf;
    last_sigma = sigma;
    const double next_cut = fixed ? cut : std::max({cut * 0.5, k::kTukeyC * sigma, min_cut});
    const bool final_scale = next_cut >= cut;
    cut = std::min(cut, next_cut);
    // The cut-off stopped shrinking on the subsample's scale: from now on every point (scale re-estimated
    // on all of them, this iteration's fit on all of them). Not at the first iteration: a start a few tenths
    // of a degree off the surface (last frame's plane) spreads the residuals so that the scale asks for a
    // cut-off above the first one; that start needs the wide iterations, and they need only the subsample.
    if (final_scale && shrinking && it > 0) {
      // Unless this is already the other refinement's plane: then the iterations on every point would
      // converge to it (see kJoinNormal).
      if (joins()) return joined_fit();
      shrinking = false;
      --it;
      continue;
    }
    // Tukey-weighted moments, sums in float over blocks of 256 points, added up in double.
    double S[10];
    kern::tukey_moments(src->x.data(), src->y.data(), src->z.data(), src->padded(), plf, float(1.0 / (cut * cut)), S);
    const Moments m = Moments::from_weighted(S);
    Eigen::Vector4d next;
    if (!m.plane(ref, up, next)) return std::nullopt;
    const double dn = (next.head<3>() - cur.head<3>()).norm(), dd = std::abs(next[3] - cur[3]);
    cur = next;
    if (final_scale && dn < k::kConvergedNormal && dd < k::kConvergedDistM) break;
    // Already at the other refinement's plane: also while the cut-off, near its final value, still creeps
    // down by a percent per iteration on the subsample (two to three iterations before it stops).
    if (joins()) return joined_fit();
    // A fixed cut-off's refit (the ceiling's tight refit) from `join`'s plane whose first step is this small
    // ends within kJoinNormal / kJoinDistM of it (the steps shrink geometrically, by <= 2/3 measured): it is
    // that plane.
    if (fixed && join && it == 0 && dn < k::kJoinNormal * k::kStillStepFraction &&
        dd < k::kJoinDistM * k::kStillStepFraction)
      return joined_fit();
  }
  return Fit{cur, last_sigma, false, cut};
}

bool RingPlaneFit::fit(const Candidates& c, const Eigen::Vector3d& up_in, const Eigen::Vector4d* previous,
                       PlaneRole role, Eigen::Vector4d& plane) {
  if (c.size() < size_t(k::kMinCandidatePoints) || c.rings() < 1) return false;
  const Eigen::Vector3d up = up_in.normalized();
  // The subsamples every score is computed on (every kStartStride-th / kFinalStride-th candidate), copied
  // once: the scores then stream a small contiguous array instead of striding through all candidates.
  start_stride_ = c.start_stride > 0 ? c.start_stride : k::kStartStride;
  final_stride_ = c.final_stride > 0 ? c.final_stride : k::kFinalStride;
  const size_t n = c.size();
  xs_ = c.x.data();
  ys_ = c.y.data();
  zs_ = c.z.data();
  np_ = (n + 3) & ~size_t(3);  // NaN-padded (Candidates)
  n_ = n;
  cand_ = &c;
  // A plane followed steadily: last frame's plane is this role's last result and the search is not due.
  Steady& st = steady_[role == PlaneRole::kCeiling ? 0 : 1];
  const bool steady = previous && st.left > 0 && *previous == st.plane;
  if (!steady) st.left = 0;
  // Every stride-th candidate into a subsample.
  auto fill = [&](auto* sub, size_t stride) {
    sub->resize((n + stride - 1) / stride);
    if (ck::available() && kern::wide()) {
      ck::strided(xs_, ys_, zs_, sub->n, stride, sub->x.data(), sub->y.data(), sub->z.data());
    } else {
      for (size_t i = 0, j = 0; i < n; i += stride, ++j) {
        sub->x[j] = xs_[i];
        sub->y[j] = ys_[i];
        sub->z[j] = zs_[i];
      }
    }
    sub->pad();
  };
  if (!steady) fill(&sub_start_, start_stride_);  // (the start's subsample: only the search scores on it)
  fill(&sub_final_, final_stride_);
  const float thr = float(cfg_.inlier_threshold_m);
  auto score = [&](const Eigen::Vector4d& pl) { return score_band(sub_final_, final_stride_, pl, thr); };
  std::optional<Fit> res1;
  // The steady refinement's support, kept for its plane's (the same score of the same points): st.support below.
  std::optional<std::pair<Eigen::Vector4d, double>> scored;
  if (steady) {
    // Last frame's plane refined alone. It must keep its support (else the walls captured it) and end within a
    // step the search would not be needed for; otherwise the search runs on this scan.
    --st.left;
    const auto r = refine(up, *previous, cfg_.irls_initial_scale_m, k::kMinCutM, false, nullptr);
    const double support = r ? score(r->pl) : 0.0;
    if (r && support >= score(*previous) && support >= k::kSteadyMinSupport * st.support &&
        std::acos(std::clamp(r->pl.head<3>().dot(previous->head<3>()), -1.0, 1.0)) < k::kSteadyStepDeg * k::kDeg &&
        std::abs(r->pl[3] - (*previous)[3]) < k::kSteadyStepM) {
      res1 = r;
      scored.emplace(r->pl, support);
      ++steady_fits_;
    } else {
      st.left = 0;
      if (start_stride_ > 0) fill(&sub_start_, start_stride_);  // the start's subsample, skipped above
    }
  }
  if (!res1 && !search(c, up, previous, role, res1)) return false;
  // Ceiling only: a refit at a fixed cut-off of tight_refit_sigmas robust sigmas (>= 1 cm) of the result.
  // Where two surfaces meet (a sloped ceiling patch next to the flat ceiling) the Tukey fit at 4.7 sigma
  // settles on a compromise tilted a few tenths of a degree between them; at ~2.5 sigma only the dominant
  // surface keeps its support. The tighter of the two wins on the narrow-band support.
  auto select_band = [&](double s1, double s2) {
    return float(std::clamp(k::kSelectBandSigmas * std::min(s1, s2), k::kSelectBandMinM, cfg_.inlier_threshold_m));
  };
  if (res1 && role == PlaneRole::kCeiling && cfg_.tight_refit_sigmas > 0) {
    const double ct = std::max(cfg_.tight_refit_sigmas * res1->sigma, k::kTightMinCutM);
    // (joined: its first step showed it stays at res1's plane, within 0.01 deg / 1 mm: nothing to choose)
    if (const auto tight = refine(up, res1->pl, ct, ct, true, &*res1); tight && !tight->joined) {
      const float t_sel = select_band(res1->sigma, tight->sigma);
      if (score_band(sub_final_, final_stride_, tight->pl, t_sel) > score_band(sub_final_, final_stride_, res1->pl, t_sel)) res1 = tight;
    }
  }
  if (!res1) return false;
  plane = res1->pl;
  st.plane = plane;
  st.support = scored && scored->first == plane ? scored->second : score(plane);
  return true;
}

// The search for the start (seeds, regression, triplets, last frame's plane), its refinement and last frame's
// plane's; `res1` the better (Fit), st.left set when the plane is followed steadily from here.
bool RingPlaneFit::search(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous,
                          PlaneRole role, std::optional<Fit>& res1) {
  Steady& st = steady_[role == PlaneRole::kCeiling ? 0 : 1];
  st.left = 0;
  pick_seeds(c, up.cast<float>());
  Eigen::Vector4d cur;
  if (!choose_start(c, up, previous, cur)) return false;

  // Refine the best start and, when it was not last frame's plane, last frame's plane too. A refinement
  // that lowers the support (T band, dense subsample) diverged (walls captured it): its start is kept
  // instead. Of the two, keep the one with the higher support with the soft band narrowed to 3 robust
  // sigmas of the tighter fit (>= 1 cm): at T = 5 cm a plane tilted a few tenths of a degree through a
  // narrow corridor ceiling plus the wall tops below it scores as well as the true one; at 3 sigma it
  // loses the ceiling returns it leaves behind. (A lowered/sloped patch must not capture it either.)
  const float thr = float(cfg_.inlier_threshold_m);
  auto score = [&](const Eigen::Vector4d& pl) { return score_band(sub_final_, final_stride_, pl, thr); };
  auto select_band = [&](double s1, double s2) {
    return float(std::clamp(k::kSelectBandSigmas * std::min(s1, s2), k::kSelectBandMinM, cfg_.inlier_threshold_m));
  };
  auto refine_guarded = [&](const Eigen::Vector4d& start, const Fit* join) -> std::optional<Fit> {
    const auto r = refine(up, start, cfg_.irls_initial_scale_m, k::kMinCutM, false, join);
    if (r && (r->joined || score(r->pl) >= score(start))) return r;
    return Fit{start, cfg_.inlier_threshold_m / 3};
  };
  res1 = refine_guarded(cur, nullptr);
  // Followed steadily from here: the start was last frame's plane, or its refinement joined the start's.
  bool followed = previous && (cur - *previous).norm() <= 1e-9 && res1 && res1->pl != cur;
  if (previous && (cur - *previous).norm() > 1e-9) {
    // When the first refinement moved its start (it passed the guard), the second stops once it reaches that
    // plane: the usual case, both starts lie in the same plane's basin.
    const bool res1_refined = res1 && res1->pl != cur;
    const std::optional<Fit> res2 = refine_guarded(*previous, res1_refined ? &*res1 : nullptr);
    if (res2 && res2->joined) {
      // the same plane: nothing to choose
      followed = true;
    } else if (res2 && res1) {
      const float t_sel = select_band(res1->sigma, res2->sigma);
      if (score_band(sub_final_, final_stride_, res2->pl, t_sel) > score_band(sub_final_, final_stride_, res1->pl, t_sel)) res1 = res2;
    } else if (res2) {
      res1 = res2;
    }
  }
  if (followed && res1) st.left = std::max(cfg_.start_recheck_scans, 1) - 1;
  return bool(res1);
}

}  // namespace fploc::seg
