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

// The points i < n with |((nx x + ny y) + nz z) + d| < cut (float), minus ref, written to bx/by/bz in order;
// returns their count. Reads the arrays up to np (n rounded up to a multiple of 4; the values past n are
// ignored); writes up to 7 slots past the count.
size_t band(const float* x, const float* y, const float* z, size_t n, size_t np, const float pl[4], float cut, const float ref[3],
            float* bx, float* by, float* bz);

// dst[j] = src[j * stride] for j < m (the three arrays).
void strided(const float* x, const float* y, const float* z, size_t m, size_t stride, float* ox, float* oy, float* oz);

}  // namespace fploc::seg::ck
