// The ground-at-a-kink's point loops (kink_cells.h): four lanes or scalar, or eight with AVX2.
#include "kink_cells.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "plane_kernels.h"
#include "simd4.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "lane8.h"
#define FPLOC_KINK_WIDE 1
#else
#define FPLOC_KINK_WIDE 0
#endif

#pragma GCC diagnostic ignored "-Wpsabi"

namespace fploc::seg::kink {

namespace {
constexpr int kPerQuadrant = kAzimuths / 4;
static_assert(kAzimuths % 4 == 0, "whole sectors per quadrant");

// The tangents of the sector edges within a quadrant, and the squared band edges.
struct Edges {
  std::array<float, kPerQuadrant - 1> tan;
  std::array<float, kBandEdgesM.size()> band2;
  Edges() {
    for (int k = 1; k < kPerQuadrant; ++k) tan[size_t(k - 1)] = float(std::tan(k * M_PI / 2 / kPerQuadrant));
    for (size_t b = 0; b < kBandEdgesM.size(); ++b) band2[b] = kBandEdgesM[b] * kBandEdgesM[b];
  }
};
const Edges& edges() {
  static const Edges e;
  return e;
}

// One vector of points: the cell of each lane (-1: none). V: the float vector type, I: the int one (GCC vector
// extensions; the same expressions for four and eight lanes).
template <typename V, typename I>
__attribute__((always_inline)) inline I lanes(V x, V y, V z, V nx, V ny, V nz, V d, const Edges& e) {
  const V zero = V{} * 0.f, band_m = zero + kSectorBandM;
  const V r = nx * x + ny * y + nz * z;
  V ar = r + d;
  {
    I b;
    std::memcpy(&b, &ar, sizeof b);
    b &= 0x7fffffff;
    std::memcpy(&ar, &b, sizeof b);
  }
  const I in = ar <= band_m;  // false for NaN
  // The angle from -180 deg: that of (X, Y) = (-x, -y) from 0; its quadrant q turned onto the first (a > 0, b >= 0).
  const V X = -x, Y = -y;
  const I q0 = (X > zero) & (Y >= zero), q1 = (X <= zero) & (Y > zero), q2 = (X < zero) & (Y <= zero);
  const V a = q0 ? X : q1 ? Y : q2 ? -X : -Y;
  const V b = q0 ? Y : q1 ? -X : q2 ? -Y : X;
  const I zi = I{} * 0;
  const I q = q0 ? zi : q1 ? zi + 1 : q2 ? zi + 2 : zi + 3;
  I j = zi;
  for (const float te : e.tan) j -= b >= te * a;  // (a true comparison is -1)
  const V hx = x - r * nx, hy = y - r * ny, hz = z - r * nz;  // horizontal part
  const V h2 = hx * hx + hy * hy + hz * hz;
  I band = zi;
  for (const float e2 : e.band2) band -= h2 >= zero + e2;
  return in ? band * kAzimuths + q * kPerQuadrant + j : zi - 1;
}

// The points per cell: a ring's returns come cell after cell, so runs of one cell are added at once (an
// increment per point would wait for the last one's store).
void count_runs(const int16_t* cell, size_t m, std::array<int32_t, kCells>& count) {
  if (m == 0) return;
  int16_t cur = cell[0];
  int32_t run = 0;
  for (size_t k = 0; k < m; ++k) {
    if (cell[k] != cur) {
      count[size_t(cur)] += run;
      cur = cell[k];
      run = 0;
    }
    ++run;
  }
  count[size_t(cur)] += run;
}

size_t cells4(const float* xs, const float* ys, const float* zs, size_t n, const Eigen::Vector3f& n0, float d0,
              int32_t* index, int16_t* cell, std::array<int32_t, kCells>& count) {
  using namespace simd;
  const Edges& e = edges();
  const v4f nx = splat(n0.x()), ny = splat(n0.y()), nz = splat(n0.z()), d = splat(d0);
  size_t m = 0;
  for (size_t i = 0; i < n; i += 4) {
    const v4i sec = lanes<v4f, v4i>(load(xs + i), load(ys + i), load(zs + i), nx, ny, nz, d, e);
    for (int l = 0; l < 4; ++l) {
      if (sec[l] < 0 || i + size_t(l) >= n) continue;
      index[m] = int32_t(i + size_t(l));
      cell[m++] = int16_t(sec[l]);
    }
  }
  count_runs(cell, m, count);
  return m;
}

#if FPLOC_KINK_WIDE
using lane8::v8f;
using lane8::v8i;
constexpr lane8::CompressTable<false> kCompress;

__attribute__((target("avx2"))) size_t cells8(const float* xs, const float* ys, const float* zs, size_t n,
                                              const Eigen::Vector3f& n0, float d0, int32_t* index, int16_t* cell,
                                              std::array<int32_t, kCells>& count) {
  const Edges& e = edges();
  const v8f zero{};
  const v8f nx = zero + n0.x(), ny = zero + n0.y(), nz = zero + n0.z(), d = zero + d0;
  const size_t np = (n + 3) & ~size_t(3);  // readable
  const v8i iota{0, 1, 2, 3, 4, 5, 6, 7};
  size_t m = 0;
  for (size_t i = 0; i < n; i += 8) {
    v8f x = zero, y = zero, z = zero;
    const size_t k = i + 8 <= np ? 8 : 4;  // (np - i is 4 at the end when not 8)
    if (k == 8) {
      std::memcpy(&x, xs + i, sizeof x);
      std::memcpy(&y, ys + i, sizeof y);
      std::memcpy(&z, zs + i, sizeof z);
    } else {
      std::memcpy(&x, xs + i, 4 * sizeof(float));
      std::memcpy(&y, ys + i, 4 * sizeof(float));
      std::memcpy(&z, zs + i, 4 * sizeof(float));
    }
    const int past = n - i < 8 ? (1 << (n - i)) - 1 : 255;  // (the lanes past n: off)
    {
      // Most groups have no return near the plane (walls, the far floor beyond the band): the band test
      // alone first (lanes()'s, the same floats), the sector and band only where a lane is in.
      v8f ar = nx * x + ny * y + nz * z + d;
      v8i b;
      std::memcpy(&b, &ar, sizeof b);
      b &= 0x7fffffff;
      std::memcpy(&ar, &b, sizeof b);
      if ((_mm256_movemask_ps(reinterpret_cast<__m256>(ar <= zero + kSectorBandM)) & past) == 0) continue;
    }
    v8i sec = lanes<v8f, v8i>(x, y, z, nx, ny, nz, d, e);
    const int in = _mm256_movemask_ps(reinterpret_cast<__m256>(sec >= 0)) & past;
    v8i idx = iota + int32_t(i);
    if (in != 255) {  // the kept lanes to the front
      const __m256i perm = lane8::to_front(kCompress, in);
      idx = reinterpret_cast<v8i>(_mm256_permutevar8x32_epi32(reinterpret_cast<__m256i>(idx), perm));
      sec = reinterpret_cast<v8i>(_mm256_permutevar8x32_epi32(reinterpret_cast<__m256i>(sec), perm));
    }
    std::memcpy(index + m, &idx, sizeof idx);
    const __m256i s = reinterpret_cast<__m256i>(sec);
    const __m128i s16 = _mm_packs_epi32(_mm256_castsi256_si128(s), _mm256_extracti128_si256(s, 1));  // (cells < 2^15)
    std::memcpy(cell + m, &s16, sizeof s16);
    m += size_t(__builtin_popcount(unsigned(in)));
  }
  count_runs(cell, m, count);
  return m;
}

__attribute__((target("avx2"))) size_t near_plane8(const float* x, const float* y, const float* z, size_t n,
                                                   const Eigen::Vector3f& nrm, float d, float cut, float* ox, float* oy,
                                                   float* oz, size_t m) {
  const v8f zero{};
  const v8f nx = zero + nrm.x(), ny = zero + nrm.y(), nz = zero + nrm.z(), dv = zero + d, cv = zero + cut;
  for (size_t i = 0; i < n; i += 8) {
    v8f px, py, pz;
    std::memcpy(&px, x + i, sizeof px);
    std::memcpy(&py, y + i, sizeof py);
    std::memcpy(&pz, z + i, sizeof pz);
    v8f r = px * nx + (py * ny + pz * nz) + dv;  // (Eigen's order)
    {
      v8i b;
      std::memcpy(&b, &r, sizeof b);
      b &= 0x7fffffff;
      std::memcpy(&r, &b, sizeof b);
    }
    int in = _mm256_movemask_ps(reinterpret_cast<__m256>(r < cv));  // false for NaN
    if (n - i < 8) in &= (1 << (n - i)) - 1;
    if (in == 0) continue;
    if (in != 255) {  // the kept lanes to the front
      const __m256i perm = lane8::to_front(kCompress, in);
      px = reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(px), perm));
      py = reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(py), perm));
      pz = reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(pz), perm));
    }
    std::memcpy(ox + m, &px, sizeof px);
    std::memcpy(oy + m, &py, sizeof py);
    std::memcpy(oz + m, &pz, sizeof pz);
    m += size_t(__builtin_popcount(unsigned(in)));
  }
  return m;
}
#endif
}  // namespace

namespace {
bool g_wide_enabled = true;
}
bool wide_available() { return FPLOC_KINK_WIDE && g_wide_enabled; }
void set_wide_enabled(bool on) { g_wide_enabled = on; }

size_t near_plane(const float* x, const float* y, const float* z, size_t n, const Eigen::Vector3f& nrm, float d,
                  float cut, float* ox, float* oy, float* oz, size_t m) {
#if FPLOC_KINK_WIDE
  if (g_wide_enabled && kern::wide()) return near_plane8(x, y, z, n, nrm, d, cut, ox, oy, oz, m);
#endif
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p(x[i], y[i], z[i]);
    if (!(std::abs(nrm.dot(p) + d) < cut)) continue;
    ox[m] = p.x();
    oy[m] = p.y();
    oz[m] = p.z();
    ++m;
  }
  return m;
}

size_t cells(const float* x, const float* y, const float* z, size_t n, const Eigen::Vector3f& n0, float d0,
             int32_t* index, int16_t* cell, std::array<int32_t, kCells>& count) {
#if FPLOC_KINK_WIDE
  if (g_wide_enabled && kern::wide()) return cells8(x, y, z, n, n0, d0, index, cell, count);
#endif
  return cells4(x, y, z, n, n0, d0, index, cell, count);
}

}  // namespace fploc::seg::kink
