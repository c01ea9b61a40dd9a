// The per-point pass of the feature extractor over one ring (internal header): LOAM's smoothness c of every
// point whose window lies in the ring, and which points may become corners or surfaces. Vectorised: four
// points at a time with GCC/Clang vector extensions (SSE2 on x86-64, the baseline target; NEON on arm64;
// scalar code elsewhere), and on x86-64 a second copy of the same code built for AVX2, chosen at run time
// when the CPU has it. Both give the same values bit for bit as the plain rules (test/reference_features.h):
//  - window sums in double: a sum of up to 2 hw + 1 floats is exact in double whatever the order (for
//    coordinates above ~2^-15 m, i.e. all but a few in a million), so sums of hw-point blocks give the
//    same dx, dy, dz as a running prefix sum;
//  - c = float(sqrt(dx^2 + dy^2 + dz^2)) / (2 hw * r): the double root rounded to float, then one float
//    division, lane by lane the same operations as one point at a time (no FMA contraction: the features
//    sources are built with -ffp-contract=off).
#pragma once
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
  std::vector<double>& d;     // the ring's coordinates in double, then the hw-point block sums
  std::vector<int32_t>& brk;  // number of column breaks among the first j neighbour pairs
};

// For every point i in [hw, n - hw): corner[i] = c_i when it is a corner candidate (usable: window
// unbroken, range within limits, not on a surface parallel to the beam; and c_i > corner threshold), else
// -inf; surface[i] = c_i when it is a usable surface candidate (c_i < surface threshold), else +inf.
// Occlusion boundaries (LOAM's unreliable points) are appended to `occlusions` as +(j + 1) when the far
// side begins at j + 1 (points j+1 .. j+hw are unusable) and -(j + 1) when it ends at j (j-hw+1 .. j);
// the caller applies them (they only take candidates away).
void smoothness(const RingIn& in, const RingRules& rules, RingScratch& scratch, float* corner, float* surface,
                std::vector<int>& occlusions);

// The dispatch's choice, for the benchmark and the notes: "avx2", "sse2" or "generic".
const char* smoothness_isa();

}  // namespace fploc::feat::detail
