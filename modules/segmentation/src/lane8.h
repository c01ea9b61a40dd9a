// Eight-float-lane helpers shared by the segmenter's AVX2 kernels (compact_kernels.cpp, wall_kernels.cpp):
// GCC vector types, unaligned load/store, a splat, and the lane-compression table that moves a mask's set
// lanes to the front. Private to modules/segmentation; include only under `defined(__x86_64__) &&
// defined(__GNUC__)`. Every function is compiled for AVX2 alone (no -march flag; callers dispatch).
#pragma once
#include <immintrin.h>

#include <cstdint>
#include <cstring>

namespace fploc::seg::lane8 {

typedef float v8f __attribute__((vector_size(32)));
typedef int32_t v8i __attribute__((vector_size(32)));

// For each 8-bit lane mask: the source lane of each output slot (4 bits per slot), the set lanes first in
// order. The slots after them: lane 0 (kRepeatFirst false), or the first set lane, which is always a valid
// candidate (kRepeatFirst true).
template <bool kRepeatFirst>
struct CompressTable {
  uint32_t e[256];
  constexpr CompressTable() : e{} {
    for (int m = 0; m < 256; ++m) {
      uint32_t v = 0;
      int k = 0, first = 0;
      for (int l = 7; l >= 0; --l)
        if ((m >> l) & 1) first = l;
      for (int l = 0; l < 8; ++l)
        if ((m >> l) & 1) v |= uint32_t(l) << (4 * k++);
      if (kRepeatFirst)
        for (; k < 8; ++k) v |= uint32_t(first) << (4 * k);
      e[m] = v;
    }
  }
};

__attribute__((target("avx2"))) inline v8f ld(const float* p) {
  v8f v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
__attribute__((target("avx2"))) inline void st(float* p, v8f v) { std::memcpy(p, &v, sizeof v); }
__attribute__((target("avx2"))) inline v8f splat(float a) { return v8f{a, a, a, a, a, a, a, a}; }

// The lane permutation (for _mm256_permutevar8x32_*) that moves the set lanes of an 8-bit mask to the front, from
// the table's entry for the mask.
template <bool kRepeatFirst>
__attribute__((target("avx2"))) inline __m256i to_front(const CompressTable<kRepeatFirst>& table, int mask) {
  const __m256i shifts = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
  return _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32(int(table.e[mask])), shifts), _mm256_set1_epi32(15));
}

}  // namespace fploc::seg::lane8
