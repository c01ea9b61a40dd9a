#include "smoothness.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define FPLOC_FEAT_AVX2_COPY 1
#else
#define FPLOC_FEAT_AVX2_COPY 0
#endif

namespace fploc::feat::detail {

#define FEAT_NS base
#define FEAT_ATTR
#define FEAT_AVX 0
#include "smoothness_kernel.inc"
#undef FEAT_NS
#undef FEAT_ATTR
#undef FEAT_AVX

#if FPLOC_FEAT_AVX2_COPY
#define FEAT_NS avx2
#define FEAT_ATTR __attribute__((target("avx2")))
#define FEAT_AVX 1
#include "smoothness_kernel.inc"
#undef FEAT_NS
#undef FEAT_ATTR
#undef FEAT_AVX
#endif

namespace {
using Pass = void (*)(const RingIn&, const RingRules&, RingScratch&, float*, uint64_t*, float*, std::vector<int>&);
struct Choice {
  Pass pass;
  int (*argmax)(const float*, int, int);
  const char* name;
};
// FPLOC_FEATURES_ISA=base forces the baseline copy (tests run both copies against the plain rules).
Choice choose() {
  const char* force = std::getenv("FPLOC_FEATURES_ISA");
  const bool base_only = force && std::strcmp(force, "base") == 0;
#if FPLOC_FEAT_AVX2_COPY
  if (!base_only && __builtin_cpu_supports("avx2")) return {&avx2::pass, &avx2::first_argmax, "avx2"};
#else
  (void)base_only;
#endif
#if defined(__SSE2__)
  return {&base::pass, &base::first_argmax, "sse2"};
#else
  return {&base::pass, &base::first_argmax, "generic"};
#endif
}
const Choice& choice() {
  static const Choice c = choose();
  return c;
}
}  // namespace

float squared_above(float t) {
  if (std::isnan(t)) return t;
  if (t < 0) return -std::numeric_limits<float>::infinity();  // every root (>= 0) is above
  if (std::isinf(t)) return t;
  const float inf = std::numeric_limits<float>::infinity();
  float q = t * t;
  if (std::isinf(q)) q = std::numeric_limits<float>::max();
  while (std::sqrt(q) > t) q = std::nextafter(q, -inf);
  for (float u = std::nextafter(q, inf); std::sqrt(u) <= t; u = std::nextafter(q, inf)) q = u;
  return q;
}

float squared_below(float s) {
  if (std::isnan(s)) return s;
  const float inf = std::numeric_limits<float>::infinity();
  if (s <= 0) return -inf;  // no root (>= 0) is below
  if (std::isinf(s)) return s;
  float q = s * s;
  if (std::isinf(q)) q = std::numeric_limits<float>::max();
  while (std::sqrt(q) < s) q = std::nextafter(q, inf);
  for (float d = std::nextafter(q, -inf); d >= 0 && std::sqrt(d) >= s; d = std::nextafter(q, -inf)) q = d;
  return q;
}

void smoothness(const RingIn& in, const RingRules& rules, RingScratch& scratch, float* corner, uint64_t* surface,
                float* surface_c, std::vector<int>& occlusions) {
  RingRules ru = rules;
  ru.corner_sq = squared_above(rules.corner);
  ru.surface_sq = squared_below(rules.surface);
  choice().pass(in, ru, scratch, corner, surface, surface_c, occlusions);
}

int first_argmax(const float* v, int b, int e) { return choice().argmax(v, b, e); }

const char* smoothness_isa() { return choice().name; }

}  // namespace fploc::feat::detail
