// Ouster's published beam model (sensor manual; ouster-sdk make_xyz_lut), as a precomputed look-up
// table: point = range * direction + offset, in metres in the sensor frame.
#pragma once
#include <Eigen/Core>
#include <vector>

#include "fploc/core/scan.h"

namespace fploc {

struct XyzLut {
  int height = 0, width = 0;
  // Per pixel (row-major [beam][measurement id]): unit direction scaled for mm->m and offset [m].
  Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> direction;
  Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> offset;
};

// Builds the table for `width` columns per frame. Column index = measurement id (staggered data).
XyzLut make_xyz_lut(const BeamIntrinsics& beams, int width);

// XYZ [m] of one pixel (beam, measurement id) at range r_mm. Invalid (r_mm == 0) gives NaN.
inline Eigen::Vector3f lut_point(const XyzLut& lut, int beam, int mid, uint32_t r_mm) {
  const size_t i = size_t(beam) * lut.width + mid;
  if (r_mm == 0) return Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  return lut.direction.row(i).transpose() * float(r_mm) + lut.offset.row(i).transpose();
}

// All pixels of a scan in the sensor frame, row-major [beam][column] (NaN where there is no return).
void scan_to_xyz(const Scan& scan, const XyzLut& lut, std::vector<Eigen::Vector3f>& out);

// Column index after destaggering: destaggered[u][(v + shift[u]) mod W] = staggered[u][v].
inline int destagger_column(const BeamIntrinsics& b, int beam, int col, int width) {
  const int s = beam < int(b.pixel_shift_by_row.size()) ? b.pixel_shift_by_row[beam] : 0;
  return ((col + s) % width + width) % width;
}

}  // namespace fploc
