// The plane fit's compaction and strided copies eight points at a time (see compact_kernels.h), compiled for
// AVX2 alone (no -march flag; without FMA the band test rounds as the four-lane loop's).
#include "compact_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fploc/segmentation/candidates.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "lane8.h"
#define FPLOC_CK_WIDE 1
#else
#define FPLOC_CK_WIDE 0
#endif

#pragma GCC diagnostic ignored "-Wpsabi"

namespace fploc::seg::ck {

float boxes_scalar(const float* x, const float* y, const float* z, size_t n, float* box, size_t stride) {
  constexpr size_t B = Candidates::kBoxPoints;
  float m = 0;
  for (size_t k0 = 0, k = 0; k0 < n; k0 += B, ++k) {
    float r[6] = {x[k0], y[k0], z[k0], x[k0], y[k0], z[k0]};
    for (size_t i = k0 + 1; i < n && i < k0 + B; ++i) {
      r[0] = std::min(r[0], x[i]);
      r[1] = std::min(r[1], y[i]);
      r[2] = std::min(r[2], z[i]);
      r[3] = std::max(r[3], x[i]);
      r[4] = std::max(r[4], y[i]);
      r[5] = std::max(r[5], z[i]);
    }
    for (int a = 0; a < 6; ++a) {
      box[size_t(a) * stride + k] = r[a];
      m = std::max(m, std::abs(r[a]));
    }
  }
  return m;
}

#if FPLOC_CK_WIDE
namespace {
using lane8::ld;
using lane8::splat;
using lane8::st;
using lane8::v8f;
using lane8::v8i;
constexpr lane8::CompressTable<false> kCompress;
// src[0], src[3], ..., src[21] (perm: 0, 3, 6, 1, 4, 7, 2, 5).
__attribute__((target("avx2"))) inline v8f every3(const float* p, __m256i perm) {
  __m256 a, b, c;
  std::memcpy(&a, p, sizeof a);
  std::memcpy(&b, p + 8, sizeof b);
  std::memcpy(&c, p + 16, sizeof c);
  const __m256 t = _mm256_blend_ps(_mm256_blend_ps(a, b, 0x92), c, 0x24);
  return reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(t, perm));
}
}  // namespace

namespace {
bool g_enabled = true;
}
bool available() { return g_enabled; }
void set_enabled(bool on) { g_enabled = on; }

__attribute__((target("avx2"))) size_t band(const float* x, const float* y, const float* z, size_t n, size_t np,
                                            const float pl[4], float cut, const float ref[3], float* bx, float* by, float* bz,
                                            const BoxRange* box) {
  const v8f nx = splat(pl[0]), ny = splat(pl[1]), nz = splat(pl[2]), d = splat(pl[3]), cb = splat(cut);
  const v8f rx = splat(ref[0]), ry = splat(ref[1]), rz = splat(ref[2]);
  const v8i absm = {0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff};
  size_t m = 0;
  constexpr size_t B = Candidates::kBoxPoints;
  for (size_t k0 = 0; k0 < n; k0 += B) {
  if (box && (box->lo(k0 / B) >= cut || box->hi(k0 / B) <= -cut)) continue;  // no |r| < cut in this block
  const size_t ke = std::min(n, k0 + B);
  for (size_t i = k0; i < ke; i += 8) {
    v8f px, py, pz;
    if (i + 8 <= np) {
      px = ld(x + i);
      py = ld(y + i);
      pz = ld(z + i);
    } else {  // the last four of np (the arrays may end there)
      px = py = pz = v8f{};
      std::memcpy(&px, x + i, 4 * sizeof(float));
      std::memcpy(&py, y + i, 4 * sizeof(float));
      std::memcpy(&pz, z + i, 4 * sizeof(float));
    }
    const v8f r = nx * px + ny * py + nz * pz + d;
    const v8f a = reinterpret_cast<v8f>(reinterpret_cast<v8i>(r) & absm);
    int in = _mm256_movemask_ps(reinterpret_cast<__m256>(a < cb));
    if (n - i < 8) in &= (1 << (n - i)) - 1;
    if (in == 0) continue;
    const v8f qx = px - rx, qy = py - ry, qz = pz - rz;
    if (in == 255) {
      st(bx + m, qx);
      st(by + m, qy);
      st(bz + m, qz);
      m += 8;
      continue;
    }
    const __m256i idx = lane8::to_front(kCompress, in);
    st(bx + m, reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(qx), idx)));
    st(by + m, reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(qy), idx)));
    st(bz + m, reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(qz), idx)));
    m += size_t(__builtin_popcount(unsigned(in)));
  }
  }
  return m;
}

// The smallest lane of v (exact: a minimum).
__attribute__((target("avx2"))) inline float hmin(__m256 v) {
  __m128 a = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  a = _mm_min_ps(a, _mm_movehl_ps(a, a));
  a = _mm_min_ss(a, _mm_shuffle_ps(a, a, 1));
  return _mm_cvtss_f32(a);
}

__attribute__((target("avx2"))) float boxes(const float* x, const float* y, const float* z, size_t n, float* box,
                                            size_t stride) {
  constexpr size_t B = Candidates::kBoxPoints;
  const size_t full = n / B;
  const __m256 sign = _mm256_set1_ps(-0.f);
  __m256 mx = _mm256_setzero_ps();  // largest |coordinate| (max of -min and max)
  for (size_t k = 0; k < full; ++k) {
    const size_t k0 = k * B;
    __m256 lx = _mm256_loadu_ps(x + k0), ly = _mm256_loadu_ps(y + k0), lz = _mm256_loadu_ps(z + k0);
    __m256 hx = lx, hy = ly, hz = lz;
    for (size_t i = k0 + 8; i < k0 + B; i += 8) {
      const __m256 px = _mm256_loadu_ps(x + i), py = _mm256_loadu_ps(y + i), pz = _mm256_loadu_ps(z + i);
      lx = _mm256_min_ps(lx, px);
      ly = _mm256_min_ps(ly, py);
      lz = _mm256_min_ps(lz, pz);
      hx = _mm256_max_ps(hx, px);
      hy = _mm256_max_ps(hy, py);
      hz = _mm256_max_ps(hz, pz);
    }
    // maxima as minima of the negated values (negation is exact)
    box[k] = hmin(lx);
    box[stride + k] = hmin(ly);
    box[2 * stride + k] = hmin(lz);
    box[3 * stride + k] = -hmin(_mm256_xor_ps(hx, sign));
    box[4 * stride + k] = -hmin(_mm256_xor_ps(hy, sign));
    box[5 * stride + k] = -hmin(_mm256_xor_ps(hz, sign));
    mx = _mm256_max_ps(mx, _mm256_max_ps(_mm256_max_ps(_mm256_xor_ps(lx, sign), hx),
                                         _mm256_max_ps(_mm256_max_ps(_mm256_xor_ps(ly, sign), hy),
                                                       _mm256_max_ps(_mm256_xor_ps(lz, sign), hz))));
  }
  float m = -hmin(_mm256_xor_ps(mx, sign));
  if (full * B < n) {  // the last, partial block
    float tail[6];
    const float t = boxes_scalar(x + full * B, y + full * B, z + full * B, n - full * B, tail, 1);
    for (int a = 0; a < 6; ++a) box[size_t(a) * stride + full] = tail[a];
    m = std::max(m, t);
  }
  return m;
}

__attribute__((target("avx2"))) void strided(const float* x, const float* y, const float* z, size_t m, size_t stride,
                                             float* ox, float* oy, float* oz) {
  size_t j = 0;
  if (stride == 3) {  // the reference sensor's support subsample: three loads, two blends, one permutation per 8
    const __m256i perm = _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5);
    for (; j + 8 <= m && (j + 8) * 3 <= 3 * m - 2; j += 8) {  // reads src[3j .. 3j + 23] (all before 3(m-1)+1)
      st(ox + j, every3(x + 3 * j, perm));
      st(oy + j, every3(y + 3 * j, perm));
      st(oz + j, every3(z + 3 * j, perm));
    }
  } else if (stride < (size_t(1) << 27)) {
    const int s = int(stride);
    const __m256i idx = _mm256_setr_epi32(0, s, 2 * s, 3 * s, 4 * s, 5 * s, 6 * s, 7 * s);
    for (; j + 8 <= m; j += 8) {
      const size_t i = j * stride;
      st(ox + j, reinterpret_cast<v8f>(_mm256_i32gather_ps(x + i, idx, 4)));
      st(oy + j, reinterpret_cast<v8f>(_mm256_i32gather_ps(y + i, idx, 4)));
      st(oz + j, reinterpret_cast<v8f>(_mm256_i32gather_ps(z + i, idx, 4)));
    }
  }
  for (; j < m; ++j) {
    ox[j] = x[j * stride];
    oy[j] = y[j * stride];
    oz[j] = z[j * stride];
  }
}
#else
bool available() { return false; }
void set_enabled(bool) {}
size_t band(const float*, const float*, const float*, size_t, size_t, const float*, float, const float*, float*, float*, float*,
            const BoxRange*) {
  return 0;
}
float boxes(const float* x, const float* y, const float* z, size_t n, float* box, size_t stride) {
  return boxes_scalar(x, y, z, n, box, stride);
}
void strided(const float*, const float*, const float*, size_t, size_t, float*, float*, float*) {}
#endif

}  // namespace fploc::seg::ck
