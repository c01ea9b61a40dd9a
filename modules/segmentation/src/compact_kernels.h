// Compaction and strided copies of the plane fit's point arrays eight points at a time (AVX2, chosen at run
// time with the plane fit's kernels: kern::wide()); internal header. Data movement and the same float test as
// the four-lane loops of ring_plane_fit.cpp (no fused multiply-add): the same points, bit for bit.
#pragma once
#include <cstddef>
#include <cstdint>

namespace fploc::seg::ck {

// Whether this build has the eight-lane loops (x86-64 with GCC/Clang) and they are not switched off; they run
// only where kern::wide().
bool available();
// Tests: switch the eight-lane loops off (the four-lane ones run) or on again.
void set_enabled(bool on);

// The residual range of a plane over the boxes of Candidates (candidates.h): an interval [lo, hi] holding the
// float residual ((nx x + ny y) + nz z) + d (fused multiply-adds or not, any order of the three products) of
// every point in block k. The exact range over the box, evaluated in float, widened by eps = 1e-5 of the
// largest magnitude the sum's terms can reach among the points (|d| + (|nx| + |ny| + |nz|) box_r): the float
// rounding of a residual and of the range itself are each below 4e-7 of that.
struct BoxRange {
  const float *lx, *ly, *lz, *hx, *hy, *hz;  // per axis the box side giving the smallest / largest n_a coordinate
  float nx, ny, nz, dlo, dhi;
  BoxRange(const float* box, size_t stride, float r, const float pl[4]) : nx(pl[0]), ny(pl[1]), nz(pl[2]) {
    const float* lo[3] = {box, box + stride, box + 2 * stride};
    const float* hi[3] = {box + 3 * stride, box + 4 * stride, box + 5 * stride};
    lx = pl[0] >= 0 ? lo[0] : hi[0];
    hx = pl[0] >= 0 ? hi[0] : lo[0];
    ly = pl[1] >= 0 ? lo[1] : hi[1];
    hy = pl[1] >= 0 ? hi[1] : lo[1];
    lz = pl[2] >= 0 ? lo[2] : hi[2];
    hz = pl[2] >= 0 ? hi[2] : lo[2];
    const auto fabs_ = [](float v) { return v < 0 ? -v : v; };
    const float eps = 1e-5f * (fabs_(pl[3]) + (fabs_(pl[0]) + fabs_(pl[1]) + fabs_(pl[2])) * r);
    dlo = pl[3] - 2 * eps;  // (2 eps: the float rounding of d -+ eps itself is far below eps)
    dhi = pl[3] + 2 * eps;
  }
  float lo(size_t k) const { return ((nx * lx[k] + ny * ly[k]) + nz * lz[k]) + dlo; }
  float hi(size_t k) const { return ((nx * hx[k] + ny * hy[k]) + nz * hz[k]) + dhi; }
};

// The points i < n with |((nx x + ny y) + nz z) + d| < cut (float), minus ref, written to bx/by/bz in order;
// returns their count. Reads the arrays up to np (n rounded up to a multiple of 4; the values past n are
// ignored); writes up to 7 slots past the count. box (or null): the plane's residual range over the points'
// bounding boxes per block of Candidates::kBoxPoints; a block whose range lies wholly outside (-cut, cut) is
// not read: the same result.
size_t band(const float* x, const float* y, const float* z, size_t n, size_t np, const float pl[4], float cut, const float ref[3],
            float* bx, float* by, float* bz, const BoxRange* box = nullptr);

// Bounding boxes of the points [k B, (k+1) B) below n, B = Candidates::kBoxPoints: min x, y, z, max x, y, z
// into box[0 .. 6 stride) (six arrays of stride >= (n + B - 1) / B floats); returns the largest |coordinate|.
// The points below n are finite. (Eight lanes where available() and kern::wide(); boxes_scalar anywhere: the
// same boxes.)
float boxes(const float* x, const float* y, const float* z, size_t n, float* box, size_t stride);
float boxes_scalar(const float* x, const float* y, const float* z, size_t n, float* box, size_t stride);

// dst[j] = src[j * stride] for j < m (the three arrays).
void strided(const float* x, const float* y, const float* z, size_t m, size_t stride, float* ox, float* oy, float* oz);

}  // namespace fploc::seg::ck
