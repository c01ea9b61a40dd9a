// The per-point pass of the feature extractor over one ring (internal header): LOAM's smoothness c of every
// point whose window lies in the ring, and which points may become corners or surfaces. Vectorised: eight
// points at a time in float with GCC/Clang vector extensions (SSE2 halves on x86-64, the baseline target;
// NEON on arm64; scalar code elsewhere), and on x86-64 a second copy of the same code built for AVX2, chosen
// at run time when the CPU has it.
//
// Exact picks from float arithmetic: the pass computes c~ in float (window sums of hw-point blocks, one
// root, one reciprocal) and a bound B with |c~ - c| <= B, c being the smoothness of the plain rules
// (exact_smoothness below: window sums in double, root in double rounded to float, one float division).
// The bound follows from the float rounding errors (see smoothness_kernel.inc); where it cannot decide a
// threshold test the pass computes c exactly, and the caller computes c exactly wherever an order between
// candidates is needed and the bounds overlap. So the picks are those of the plain rules, bit for bit
// (test/reference_features.h, features_test ReferenceEqual*).
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

namespace fploc::feat::detail {

struct RingIn {
  const float *x, *y, *z, *r;  // the ring's wall points (sensor frame) and ranges
  const int16_t* column;       // increasing column per point
  int n = 0;                   // points in the ring, >= 2 hw + 1
};

struct RingRules {
  int hw = 5;                  // half window
  int gap = 1;                 // a larger column step breaks the window
  float min_range = 0, max_range = 0, occlusion = 0, parallel = 0;
  float corner = 0, surface = 0;  // smoothness thresholds
};

// Buffers kept from ring to ring and scan to scan (no allocation once they have grown).
struct RingScratch {
  std::vector<float>& w;      // hw-point block sums of x, y, z
  std::vector<uint64_t>& brk;  // column breaks between neighbours as bits, and broken windows as bits
};

// The smoothness of point i (hw <= i < n - hw) by the plain rules: LOAM's c = |sum_j (X_j - X_i)| /
// (2 hw |X_i|), the window sum in double (exact for float inputs), the root in double rounded to float, one
// float division.
inline float exact_smoothness(const RingIn& in, int hw, int i) {
  double sx = 0, sy = 0, sz = 0;
  for (int k = -hw; k <= hw; ++k) {
    sx += in.x[i + k];
    sy += in.y[i + k];
    sz += in.z[i + k];
  }
  const double w = 2 * hw + 1;
  const double dx = sx - w * double(in.x[i]), dy = sy - w * double(in.y[i]), dz = sz - w * double(in.z[i]);
  return float(std::sqrt(dx * dx + dy * dy + dz * dz)) / (float(2 * hw) * in.r[i]);
}

// For every point i in [hw, n - hw) that is usable (window unbroken, range within limits, not on a surface
// parallel to the beam):
//  - corner_lo[i] <= c_i <= corner_hi[i] when it is a corner candidate (c_i > corner threshold); equal
//    bounds hold the exact c_i (where the bound could not decide the threshold); -inf / -inf otherwise;
//  - bit i of `surface` (n + 64 bits, zeroed by the caller) is set when it may be a surface candidate (its
//    lower bound is below the surface threshold: the caller computes c exactly and keeps it when c <
//    threshold); bit i of `surface_sure` (zeroed by the caller) when its upper bound is below the threshold
//    (c_i surely is).
// Occlusion boundaries (LOAM's unreliable points) are appended to `occlusions` as +(j + 1) when the far
// side begins at j + 1 (points j+1 .. j+hw are unusable) and -(j + 1) when it ends at j (j-hw+1 .. j);
// the caller applies them (they only take candidates away).
void smoothness(const RingIn& in, const RingRules& rules, RingScratch& scratch, float* corner_lo, float* corner_hi,
                uint64_t* surface, uint64_t* surface_sure, std::vector<int>& occlusions);

// Sector scans of the corner bounds, with the same instruction set as the pass: the largest of v[b .. e)
// (-inf when empty; v holds no NaN), and the indices i in [b, e) with v[i] >= t appended in increasing order.
float range_max(const float* v, int b, int e);
void indices_at_least(const float* v, float t, int b, int e, std::vector<int>& out);

// The dispatch's choice, for the benchmark and the notes: "avx2", "sse2" or "generic".
const char* smoothness_isa();

}  // namespace fploc::feat::detail
