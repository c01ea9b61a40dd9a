// Wall selection's point loops eight candidates at a time (AVX2, chosen at run time with the plane fit's
// kernels: kern::wide()); internal header. Data movement and the same float tests as the four-lane loop of
// wall_select.cpp (no fused multiply-add): the same wall points, bit for bit.
#pragma once
#include <cstddef>
#include <cstdint>

namespace fploc::seg::wallk {

// Whether this build has the eight-lane loops (x86-64 with GCC/Clang) and they are not switched off; they run
// only where kern::wide().
bool available();
// Tests: switch the eight-lane loops off (the four-lane ones run) or on again.
void set_enabled(bool on);

// The two bounds: a wall point has nc.p > mdc (below the ceiling) and nf.p > mdf (above the floor), each sum
// taken as (n.x x + n.y y) + n.z z in float.
struct Bounds {
  float ncx, ncy, ncz, mdc, nfx, nfy, nfz, mdf;
};

// Lane masks of the groups of eight candidates a, a + 8, ... < b (lanes at or past b: 0); returns the number
// of set bits. Reads up to 7 floats past b.
size_t masks8(const float* x, const float* y, const float* z, int32_t a, int32_t b, const Bounds& bd, uint8_t* masks);

// The candidates' arrays (read up to 7 entries past a piece's end).
struct Source {
  const float *x, *y, *z, *range;
  const int32_t* pixel;
};
// Per return as measured (de-skewed scans): x = dir_x[pix] fr + off_x[pix] etc. with fr = range_mm[pix]
// (the table per pixel when the look-up column is the scan's own).
struct Measured {
  const float* lut[6];
  const uint32_t* range_mm;
};
struct Out {
  float *x, *y, *z, *range, *t;
  int16_t *ring, *col;
};
// Copies the wall points of candidates [a, b) of scan row u (first pixel `row`, destaggered column = pixel + off)
// to out from index o on; col_dt: per staggered column time; meas: non-null for de-skewed scans. The output
// arrays must have 8 writable entries past the last point. Returns the new o.
size_t copy8(const Source& s, int32_t a, int32_t b, int32_t row, int32_t off, int16_t u, const uint8_t* masks,
             const float* col_dt, const Measured* meas, const Out& out, size_t o);

}  // namespace fploc::seg::wallk
