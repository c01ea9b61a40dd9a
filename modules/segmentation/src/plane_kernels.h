// The point loops of the plane fit and plane quality (internal header): the residuals' median bin, Tukey moments,
// soft support score, inlier moments. Each runs four lanes (SSE2 on any x86-64, NEON, or scalar), or eight
// lanes with FMA (AVX2) where the CPU has them, chosen once at run time (no -march flags needed: the wide
// versions are compiled for that target alone, see plane_kernels.cpp). The eight-lane sums add the same
// terms in another order (and with fused multiply-adds), so results differ from the four-lane ones in the
// last float bits; FPLOC_SIMD=sse2 in the environment forces the four-lane versions.
#pragma once
#include <cstddef>
#include <cstdint>

#include "segmenter_constants.h"

namespace fploc::seg::ck {
struct BoxRange;
}

namespace fploc::seg::kern {

// A plane n.p + d = 0 as floats (the residual r = n.p + d).
struct PlaneF {
  float nx, ny, nz, d;
};

// Whether the eight-lane versions run (the CPU has AVX2 and FMA, and FPLOC_SIMD is not "sse2").
bool wide();
// Tests: force the four-lane versions (false) or the default choice (true).
void set_wide(bool on);

// The robust scale's bin: of the residuals |r| < cutf among the np points (np a multiple of 4; padding points
// lie outside cutf), `inside` = their count, and the returned bin B is the smallest with
// 2 #{floor(|r| inv_bin) <= B} >= inside (kScaleBins - 1 at most), i.e. the median's bin of a histogram with
// kScaleBins bins. v (np floats) is scratch. hint >= 0: a guess of the bin (fewer counting passes when it is
// near; the result does not depend on it).
int residual_scale(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_bin, float cutf,
                   float* v, int& inside, int hint = -1);

// Tukey-weighted moments w, w x, w y, w z, w xx, w xy, w xz, w yy, w yz, w zz with w = (1 - r^2 inv_c2)^2 for
// r^2 inv_c2 < 1, float sums over blocks of 256 points added in double. The padding must weigh 0 (finite
// points far off the plane).
void tukey_moments(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_c2, double S[10]);

// Soft support: sum of max(0, 1 - r^2 inv_b2) (NaN padding adds 0) and the count of r < beyond.
void soft_score(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float inv_b2, float beyond,
                float& soft, int& beyond_count);

// Inliers |r| < thr: count, moments of (p - ref) (x, y, z, xx, xy, xz, yy, yz, zz) and sum r^2; returns r < -bthr
// counted in beyond_count. NaN padding counts nowhere. box (or null): the plane's residual range over the
// bounding boxes of the n points (the rest is padding) per block of Candidates::kBoxPoints; a block whose range
// has no inlier and is wholly beyond or wholly not is not read (the same results: it adds zeros to the sums).
void inlier_moments(const float* x, const float* y, const float* z, size_t np, PlaneF pl, float thr, float bthr,
                    const float ref[3], double S[9], double& r2, int& count, int& beyond_count, size_t n = 0,
                    const ck::BoxRange* box = nullptr);

}  // namespace fploc::seg::kern
