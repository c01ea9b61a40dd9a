// Four-lane float vectors for the segmenter's point passes (internal header). GCC/Clang vector extensions:
// plain SSE2 code on x86-64 (the project's baseline target), NEON on arm64, scalar code elsewhere; no
// intrinsics, no run-time dispatch. Lane l of a pass over an array handles the elements i with i % 4 == l.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "fploc/segmentation/candidates.h"

namespace fploc::seg::simd {

typedef float v4f __attribute__((vector_size(16)));
typedef int32_t v4i __attribute__((vector_size(16)));

inline v4f load(const float* p) {
  v4f v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(float* p, v4f v) { std::memcpy(p, &v, sizeof v); }
inline void store(int32_t* p, v4i v) { std::memcpy(p, &v, sizeof v); }
inline v4f splat(float a) { return v4f{a, a, a, a}; }
inline v4i splati(int32_t a) { return v4i{a, a, a, a}; }
// max(0, q) per lane; 0 for NaN (the same as maxss(q, 0)).
inline v4f max0(v4f q) { return q > splat(0.f) ? q : splat(0.f); }
inline v4f abs(v4f a) {
  v4i b;
  std::memcpy(&b, &a, sizeof b);
  b &= splati(0x7fffffff);
  std::memcpy(&a, &b, sizeof a);
  return a;
}
// Bit l set when lane l of the comparison result `m` (0 / -1 per lane) is true.
inline int movemask(v4i m) {
#if defined(__SSE2__)
  __m128i v;
  std::memcpy(&v, &m, sizeof v);
  return _mm_movemask_ps(_mm_castsi128_ps(v));
#else
  return (m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8);
#endif
}
// Lanes summed pairwise: (l0 + l1) + (l2 + l3).
inline float hsum(v4f v) { return (v[0] + v[1]) + (v[2] + v[3]); }
inline int32_t hsum(v4i v) { return (v[0] + v[1]) + (v[2] + v[3]); }

}  // namespace fploc::seg::simd
