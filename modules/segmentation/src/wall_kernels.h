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
// zrow: null, or the row's z direction and offset (one value each, the same floats as the table's) when z is not
// stored: z = zrow[0] fr + zrow[1] with fr taken back from the candidate's range [m] (fr * 1e-3f in float) as the
// nearest integer to range * 1000 in float, which is fr exactly for fr < kExactRangeMm (the relative error of the
// two products is below 2^-22).
struct Source {
  const float *x, *y, *z, *range;
  const int32_t* pixel;
  const float* zrow = nullptr;
};
constexpr uint32_t kExactRangeMm = 1u << 21;
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
