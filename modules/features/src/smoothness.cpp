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

void smoothness(const RingIn& in, const RingRules& rules, RingScratch& scratch, float* corner, uint64_t* surface,
                float* surface_c, std::vector<int>& occlusions) {
  choice().pass(in, rules, scratch, corner, surface, surface_c, occlusions);
}

int first_argmax(const float* v, int b, int e) { return choice().argmax(v, b, e); }

const char* smoothness_isa() { return choice().name; }

}  // namespace fploc::feat::detail
