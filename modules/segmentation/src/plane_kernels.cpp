// The plane fit's point loops in four lanes (the project's baseline target) and eight lanes with FMA (AVX2,
// compiled for that target alone and chosen at run time), from one template body (see plane_kernels.h).
#include "plane_kernels.h"

#include "compact_kernels.h"
#include "fploc/segmentation/candidates.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <type_traits>

// The eight-lane helpers are inlined into the AVX2 functions only (no AVX vector crosses a call): the ABI
// note GCC gives for them does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace fploc::seg::kern {

namespace {

#if defined(__x86_64__) && defined(__GNUC__)
#define FPLOC_SEG_WIDE 1
#define FPLOC_INLINE inline __attribute__((always_inline))
#define FPLOC_LAMBDA __attribute__((always_inline))
#else
#define FPLOC_LAMBDA
#define FPLOC_SEG_WIDE 0
#define FPLOC_INLINE inline
#endif

template <int L>
struct V {
  typedef float f __attribute__((vector_size(4 * L)));
  typedef int32_t i __attribute__((vector_size(4 * L)));
};

// Loads L floats, or only the first n (< L, the rest 0) at an array's end.
template <int L, size_t n = L>
FPLOC_INLINE typename V<L>::f load(const float* p) {
  typename V<L>::f v = {};
  std::memcpy(&v, p, n * sizeof(float));
  return v;
}
template <size_t n>
using Count = std::integral_constant<size_t, n>;
// body(j, Count<L>) for j = j0, j0 + L, ... while L points remain, then body(j, Count<4>) for the last four
// (eight lanes; every range here is a multiple of 4 points).
template <int L, class Body>
FPLOC_INLINE void for_lanes(size_t j0, size_t je, Body&& body) {
  size_t j = j0;
  for (; j + L <= je; j += L) body(j, Count<L>{});
  if constexpr (L > 4)
    if (j < je) body(j, Count<4>{});
}
template <int L>
FPLOC_INLINE typename V<L>::f splat(float a) {
  typename V<L>::f v;
  for (int l = 0; l < L; ++l) v[l] = a;
  return v;
}
template <int L>
FPLOC_INLINE typename V<L>::i splati(int32_t a) {
  typename V<L>::i v;
  for (int l = 0; l < L; ++l) v[l] = a;
  return v;
}
// Lanes 0..n-1 true (-1).
template <int L>
FPLOC_INLINE typename V<L>::i first_lanes(size_t n) {  // (a constant here: the loops' Count)
  typename V<L>::i v;
  for (int l = 0; l < L; ++l) v[l] = size_t(l) < n ? -1 : 0;
  return v;
}
template <int L>
FPLOC_INLINE typename V<L>::f vabs(typename V<L>::f a) {
  typename V<L>::i b;
  std::memcpy(&b, &a, sizeof b);
  b &= splati<L>(0x7fffffff);
  std::memcpy(&a, &b, sizeof a);
  return a;
}
// Four-lane sum (l0 + l1) + (l2 + l3); eight lanes are first folded to four (l + l+4).
template <int L>
FPLOC_INLINE float hsum(typename V<L>::f v) {
  if constexpr (L == 8) return ((v[0] + v[4]) + (v[1] + v[5])) + ((v[2] + v[6]) + (v[3] + v[7]));
  else return (v[0] + v[1]) + (v[2] + v[3]);
}
template <int L>
FPLOC_INLINE int32_t hsumi(typename V<L>::i v) {
  int32_t s = 0;
  for (int l = 0; l < L; ++l) s += v[l];
  return s;
}

// The loops: the main part L points at a time, then (eight lanes, np = 4 mod 8) the last four.
template <int L>
FPLOC_INLINE int residual_bins_t(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_bin,
                                 float cutf, float* v) {
  using F = typename V<L>::f;
  using I = typename V<L>::i;
  const F nx = splat<L>(pl.nx), ny = splat<L>(pl.ny), nz = splat<L>(pl.nz), d = splat<L>(pl.d);
  const F inv = splat<L>(inv_bin), cutv = splat<L>(cutf), inf = splat<L>(std::numeric_limits<float>::infinity());
  I cnt = splati<L>(0);
  for_lanes<L>(0, np, [&](size_t j, auto N) FPLOC_LAMBDA {
    constexpr size_t n = decltype(N)::value;
    const F a = vabs<L>(nx * load<L, n>(x + j) + ny * load<L, n>(y + j) + nz * load<L, n>(z + j) + d);
    const I in = (a < cutv) & first_lanes<L>(n);
    cnt -= in;
    const F b = in ? a * inv : inf;
    std::memcpy(v + j, &b, n * sizeof(float));
  });
  return hsumi<L>(cnt);
}

template <int L>
FPLOC_INLINE int count_below_t(const float* v, size_t np, float t) {
  using F = typename V<L>::f;
  using I = typename V<L>::i;
  const F tv = splat<L>(t);
  I c0 = splati<L>(0), c1 = splati<L>(0);
  size_t j = 0;
  for (; j + 2 * L <= np; j += 2 * L) {
    c0 -= load<L>(v + j) < tv;
    c1 -= load<L>(v + j + L) < tv;
  }
  for_lanes<L>(j, np, [&](size_t i, auto N) FPLOC_LAMBDA {
    constexpr size_t n = decltype(N)::value;
    c0 -= (load<L, n>(v + i) < tv) & first_lanes<L>(n);
  });
  return hsumi<L>(c0 + c1);
}

// The smallest bin B with 2 count(bin <= B) >= inside, by bisection over counts of v < B + 1 (for v >= 0,
// floor(v) <= B exactly when v < B + 1); B = kScaleBins - 1 (the clamped last bin) when no smaller one.
// hint (>= 0): a guess of the bin (the last iteration's scale); the same bin is found from a bracket around
// it (two counts when the guess is right) instead of from the whole range (eight counts).
template <int L>
FPLOC_INLINE int median_bin_t(const float* v, size_t np, int inside, int hint) {
  // F(B): 2 count(v < B + 1) >= inside, true from the answer on (monotone); the last bin always true.
  auto F = [&](int b) FPLOC_LAMBDA { return b >= k::kScaleBins - 1 || 2 * count_below_t<L>(v, np, float(b + 1)) >= inside; };
  int lo = 0, hi = k::kScaleBins - 1;  // the answer lies in [lo, hi]
  if (hint >= 0) {
    const int h = std::min(hint, k::kScaleBins - 1);
    if (F(h)) {  // answer <= h: find a false one below, doubling the step
      hi = h;
      for (int step = 1;; step *= 2) {
        const int b = hi - step;
        if (b < 0) break;
        if (!F(b)) {
          lo = b + 1;
          break;
        }
        hi = b;
      }
    } else {  // answer > h: find a true one above
      lo = h + 1;
      for (int step = 1;; step *= 2) {
        const int b = lo - 1 + step;
        if (b >= k::kScaleBins - 1) break;
        if (F(b)) {
          hi = b;
          break;
        }
        lo = b + 1;
      }
    }
  }
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (2 * count_below_t<L>(v, np, float(mid + 1)) >= inside) hi = mid;
    else lo = mid + 1;
  }
  return lo;
}

template <int L>
FPLOC_INLINE void tukey_moments_t(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_c2,
                                  double S[10]) {
  using F = typename V<L>::f;
  const F nx = splat<L>(pl.nx), ny = splat<L>(pl.ny), nz = splat<L>(pl.nz), d = splat<L>(pl.d);
  const F ic2 = splat<L>(inv_c2), one = splat<L>(1.f), zero = splat<L>(0.f);
  for (int q = 0; q < 10; ++q) S[q] = 0;
  for (size_t j0 = 0; j0 < np; j0 += 256) {
    F sw = zero, sx = zero, sy = zero, sz = zero, sxx = zero, sxy = zero, sxz = zero, syy = zero, syz = zero,
      szz = zero;
    for_lanes<L>(j0, std::min(np, j0 + 256), [&](size_t j, auto N) FPLOC_LAMBDA {
      constexpr size_t n = decltype(N)::value;
      const F px = load<L, n>(x + j), py = load<L, n>(y + j), pz = load<L, n>(z + j);
      const F r = nx * px + ny * py + nz * pz + d;
      const F t = r * r * ic2;
      const F u = one - t;
      const F w = (t < one) & first_lanes<L>(n) ? u * u : zero;
      const F wx = w * px, wy = w * py, wz = w * pz;
      sw += w;
      sx += wx; sy += wy; sz += wz;
      sxx += wx * px; sxy += wx * py; sxz += wx * pz;
      syy += wy * py; syz += wy * pz; szz += wz * pz;
    });
    const F all[10] = {sw, sx, sy, sz, sxx, sxy, sxz, syy, syz, szz};
    for (int q = 0; q < 10; ++q) S[q] += double(hsum<L>(all[q]));
  }
}

template <int L>
FPLOC_INLINE void soft_score_t(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_b2,
                               float beyond, float& soft_out, int& beyond_out) {
  using F = typename V<L>::f;
  using I = typename V<L>::i;
  const F nx = splat<L>(pl.nx), ny = splat<L>(pl.ny), nz = splat<L>(pl.nz), d = splat<L>(pl.d);
  const F ib2 = splat<L>(inv_b2), one = splat<L>(1.f), zero = splat<L>(0.f), bthr = splat<L>(beyond);
  F soft = zero;
  I cnt = splati<L>(0);
  for_lanes<L>(0, np, [&](size_t j, auto N) FPLOC_LAMBDA {
    constexpr size_t n = decltype(N)::value;
    const I valid = first_lanes<L>(n);
    const F r = nx * load<L, n>(x + j) + ny * load<L, n>(y + j) + nz * load<L, n>(z + j) + d;
    const F q = one - r * r * ib2;
    soft += (q > zero) & valid ? q : zero;  // max(0, q), 0 for NaN
    cnt -= (r < bthr) & valid;
  });
  soft_out = hsum<L>(soft);
  beyond_out = hsumi<L>(cnt);
}

template <int L>
FPLOC_INLINE void inlier_moments_t(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float thr,
                                   float bthr, const float ref[3], double S[9], double& r2, int& count,
                                   int& beyond_count, size_t n, const ck::BoxRange* box) {
  using F = typename V<L>::f;
  using I = typename V<L>::i;
  const F nx = splat<L>(pl.nx), ny = splat<L>(pl.ny), nz = splat<L>(pl.nz), dv = splat<L>(pl.d), zero = splat<L>(0.f);
  const F tv = splat<L>(thr), bv = splat<L>(-bthr), rx = splat<L>(ref[0]), ry = splat<L>(ref[1]), rz = splat<L>(ref[2]);
  for (int q = 0; q < 9; ++q) S[q] = 0;
  r2 = 0;
  I cntv = splati<L>(0), beyondv = splati<L>(0);
  int beyond_boxed = 0;  // the points of blocks wholly beyond (box)
  constexpr size_t B = Candidates::kBoxPoints;
  static_assert(256 % B == 0 && B % 8 == 0);
  for (size_t j0 = 0; j0 < np; j0 += 256) {
    F sx = zero, sy = zero, sz = zero, sxx = zero, sxy = zero, sxz = zero, syy = zero, syz = zero, szz = zero, sr2 = zero;
    // A block of the box without inliers adds zeros to every sum (the same sums without it); its beyond count is
    // all its points or none when its residual range says so.
    for (size_t k0 = j0; k0 < std::min(np, j0 + 256); k0 += B) {
    if (box) {
      const float lo = box->lo(k0 / B), hi = box->hi(k0 / B);
      if (lo >= thr || hi <= -thr) {
        if (lo >= -bthr) continue;
        if (hi < -bthr) {
          beyond_boxed += int(std::min(n, k0 + B) - k0);
          continue;
        }
      }
    }
    for_lanes<L>(k0, std::min(np, k0 + B), [&](size_t j, auto N) FPLOC_LAMBDA {
      constexpr size_t n = decltype(N)::value;
      const I valid = first_lanes<L>(n);
      const F px = load<L, n>(x + j), py = load<L, n>(y + j), pz = load<L, n>(z + j);
      const F r = nx * px + ny * py + nz * pz + dv;
      beyondv -= (r < bv) & valid;
      const I in = (vabs<L>(r) < tv) & valid;
      cntv -= in;
      const F qx = in ? px - rx : zero, qy = in ? py - ry : zero, qz = in ? pz - rz : zero, qr = in ? r : zero;
      sx += qx; sy += qy; sz += qz;
      sxx += qx * qx; sxy += qx * qy; sxz += qx * qz; syy += qy * qy; syz += qy * qz; szz += qz * qz;
      sr2 += qr * qr;
    });
    }
    const F all[9] = {sx, sy, sz, sxx, sxy, sxz, syy, syz, szz};
    for (int q = 0; q < 9; ++q) S[q] += double(hsum<L>(all[q]));
    r2 += double(hsum<L>(sr2));
  }
  count = hsumi<L>(cntv);
  beyond_count = hsumi<L>(beyondv) + beyond_boxed;
}

#if FPLOC_SEG_WIDE
#define FPLOC_WIDE_TARGET __attribute__((target("avx2,fma")))
FPLOC_WIDE_TARGET int residual_scale8(const float* x, const float* y, const float* z, size_t np, PlaneF pl,
                                      float inv_bin, float cutf, float* v, int& inside, int hint) {
  inside = residual_bins_t<8>(x, y, z, np, pl, inv_bin, cutf, v);
  return median_bin_t<8>(v, np, inside, hint);
}
FPLOC_WIDE_TARGET void tukey_moments8(const float* x, const float* y, const float* z, size_t np, PlaneF pl,
                                      float inv_c2, double S[10]) {
  tukey_moments_t<8>(x, y, z, np, pl, inv_c2, S);
}
FPLOC_WIDE_TARGET void soft_score8(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_b2,
                                   float beyond, float& soft, int& beyond_count) {
  soft_score_t<8>(x, y, z, np, pl, inv_b2, beyond, soft, beyond_count);
}
FPLOC_WIDE_TARGET void inlier_moments8(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float thr,
                                       float bthr, const float ref[3], double S[9], double& r2, int& count,
                                       int& beyond_count, size_t n, const ck::BoxRange* box) {
  inlier_moments_t<8>(x, y, z, np, pl, thr, bthr, ref, S, r2, count, beyond_count, n, box);
}
#endif

bool default_wide() {
#if FPLOC_SEG_WIDE
  const char* e = std::getenv("FPLOC_SIMD");
  if (e && std::strcmp(e, "sse2") == 0) return false;
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

bool g_wide = default_wide();

}  // namespace

bool wide() { return g_wide; }
void set_wide(bool on) { g_wide = on && default_wide(); }

int residual_scale(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_bin, float cutf,
                   float* v, int& inside, int hint) {
#if FPLOC_SEG_WIDE
  if (g_wide) return residual_scale8(x, y, z, np, pl, inv_bin, cutf, v, inside, hint);
#endif
  inside = residual_bins_t<4>(x, y, z, np, pl, inv_bin, cutf, v);
  return median_bin_t<4>(v, np, inside, hint);
}

void tukey_moments(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_c2, double S[10]) {
#if FPLOC_SEG_WIDE
  if (g_wide) return tukey_moments8(x, y, z, np, pl, inv_c2, S);
#endif
  tukey_moments_t<4>(x, y, z, np, pl, inv_c2, S);
}

void soft_score(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_b2, float beyond,
                float& soft, int& beyond_count) {
#if FPLOC_SEG_WIDE
  if (g_wide) return soft_score8(x, y, z, np, pl, inv_b2, beyond, soft, beyond_count);
#endif
  soft_score_t<4>(x, y, z, np, pl, inv_b2, beyond, soft, beyond_count);
}

void inlier_moments(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float thr, float bthr,
                    const float ref[3], double S[9], double& r2, int& count, int& beyond_count, size_t n,
                    const ck::BoxRange* box) {
#if FPLOC_SEG_WIDE
  if (g_wide) return inlier_moments8(x, y, z, np, pl, thr, bthr, ref, S, r2, count, beyond_count, n, box);
#endif
  inlier_moments_t<4>(x, y, z, np, pl, thr, bthr, ref, S, r2, count, beyond_count, n, box);
}

}  // namespace fploc::seg::kern
