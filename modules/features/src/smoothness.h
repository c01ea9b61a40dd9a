// The per-point pass of the feature extractor over one ring (internal header): LOAM's smoothness c of every
// point whose window lies in the ring, and which points may become corners or surfaces. Vectorised: eight
// points at a time in float with GCC/Clang vector extensions (SSE2 halves on x86-64, the baseline target;
// NEON on arm64; scalar code elsewhere), and on x86-64 a second copy of the same code built for AVX2, chosen
// at run time when the CPU has it.
//
// The smoothness is defined by its float computation (float_smoothness below: hw-point block sums in float,
// one division, one root), the same operations in the same order in every copy and in the scalar function,
// so every copy gives the same c, bit for bit (no fused multiply-adds: neither copy is built with FMA). Until
// the seventh speed round c was LOAM's value with the window sum in double and picks ordered by that exact
// value; the float value differs from it by ~1e-6 relative (the rounding of 12 float sums), which changes
// the order of two candidates only where their c agree to that precision (test/reference_features.h holds
// the plain rules with this c). Since the thirty-fourth round the pass computes q = c^2 (no root) and the picks
// follow q's order, the thresholds still applied to c (float_smoothness_sq below).
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
  // (set by smoothness() from corner / surface: the same tests on c^2 before its root, squared_above/below)
  float corner_sq = 0, surface_sq = 0;
};

// Buffers kept from ring to ring and scan to scan (no allocation once they have grown).
struct RingScratch {
  std::vector<float>& w;      // hw-point block sums of x, y, z
  std::vector<uint64_t>& brk;  // column breaks between neighbours as bits, and broken windows as bits
};

// The smoothness of point i (hw <= i < n - hw): c = |sum_j (X_j - X_i)| / |sum_j X_j| in float, as the
// vector pass computes it: block sums A = X_{i-hw} + ... + X_{i-1} and B = X_{i+1} + ... + X_{i+hw} added in
// index order, S = A + B and d = S - 2hw X_i per coordinate, c = sqrt(((dx dx + dy dy) + dz dz) / ((Sx Sx +
// Sy Sy) + Sz Sz)).
// LOAM divides by 2hw |X_i|, the point's own range; |S| is 2hw times the neighbours' mean position's, the same
// on a smooth surface (so the thresholds keep their meaning) but not under range noise: dividing by the
// point's own range makes a return nearer than the surface score higher than one as far beyond it, and the
// largest c of a sector -- the corner pick -- is then mostly a near one. On the simulator's flat walls (2 cm
// noise) the corner features stood 15-20 mm in front of the walls at 1-2 m (the plan-change detector read the
// 2.4 m corridor as 0.2 % narrower than drawn); with the neighbours' range they stand on them
// (docs/notes/perception.md, "Corner picks in front of the walls").
// q = c^2 as computed before the root (float_smoothness = its correctly rounded root). The pass stores q and the
// picks follow q's order: c's, except where two q round to the same c, whose tie q decides (then the index, as
// for equal q). Since the thirty-fourth speed round (the root was ~8 % of the pipeline's pass): a rounding-level
// change of the order, the thresholds' tests on c kept exactly (squared_above / squared_below).
inline float float_smoothness_sq(const RingIn& in, int hw, int i) {
  float ax = in.x[i - hw], ay = in.y[i - hw], az = in.z[i - hw];
  float bx = in.x[i + 1], by = in.y[i + 1], bz = in.z[i + 1];
  for (int q = 1; q < hw; ++q) {
    ax += in.x[i - hw + q];
    ay += in.y[i - hw + q];
    az += in.z[i - hw + q];
    bx += in.x[i + 1 + q];
    by += in.y[i + 1 + q];
    bz += in.z[i + 1 + q];
  }
  const float den = float(2 * hw);
  const float sx = ax + bx, sy = ay + by, sz = az + bz;
  const float dx = sx - den * in.x[i], dy = sy - den * in.y[i], dz = sz - den * in.z[i];
  return ((dx * dx + dy * dy) + dz * dz) / ((sx * sx + sy * sy) + sz * sz);
}
inline float float_smoothness(const RingIn& in, int hw, int i) { return std::sqrt(float_smoothness_sq(in, hw, i)); }

// The tests on c = sqrt(q) (correctly rounded, non-decreasing in q) as tests on q, exact for every q >= 0 and
// NaN: sqrt(q) > t  <=>  q > squared_above(t) (the largest float whose root is <= t), and sqrt(q) < s  <=>
// q < squared_below(s) (the smallest float whose root is >= s).
float squared_above(float t);
float squared_below(float s);

// For every point i in [hw, n - hw) that is usable (window unbroken, range within limits, not on a surface
// parallel to the beam), c_i = float_smoothness:
//  - corner[i] = q_i (c_i^2 before the root, float_smoothness_sq: c_i = sqrt(q_i)) when it is a corner
//    candidate (c_i > corner threshold), -inf otherwise (and for unusable points); entries outside
//    [hw, n - hw) untouched;
//  - bit i of `surface` (n + 64 bits, zeroed by the caller) set when it is a surface candidate (c_i <
//    surface threshold), and then surface_c[i] = q_i (other entries unspecified; surface_c holds room for
//    the ring's points rounded up to eight). A NaN c_i is neither.
// (q, not c: the picks need only an order, which q gives without the root.)
// Occlusion boundaries (LOAM's unreliable points) are appended to `occlusions` as +(j + 1) when the far
// side begins at j + 1 (points j+1 .. j+hw are unusable) and -(j + 1) when it ends at j (j-hw+1 .. j);
// the caller applies them (they only take candidates away).
void smoothness(const RingIn& in, const RingRules& rules, RingScratch& scratch, float* corner, uint64_t* surface,
                float* surface_c, std::vector<int>& occlusions);

// Sector scan of the corner values, with the same instruction set as the pass: the first index of the
// largest of v[b .. e), -1 when that is -inf or the range is empty (v holds no NaN).
int first_argmax(const float* v, int b, int e);

// The dispatch's choice, for the benchmark and the notes: "avx2", "sse2" or "generic".
const char* smoothness_isa();

}  // namespace fploc::feat::detail
