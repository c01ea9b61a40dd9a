#include "fploc/core/xyz.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace fploc {

XyzLut make_xyz_lut(const BeamIntrinsics& beams, int width) {
  XyzLut lut;
  lut.height = beams.beams();
  lut.width = width;
  const size_t n = size_t(lut.height) * width;
  lut.direction.resize(n, 3);
  lut.offset.resize(n, 3);
  const auto& T = beams.lidar_to_sensor;
  Eigen::Matrix3d R;
  R << T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10];
  const Eigen::Vector3d t(T[3], T[7], T[11]);  // mm
  const double n_mm = beams.beam_offset_mm;
  // The encoder angle and its direction per column, the same for every beam: computed once (the same values,
  // so the same table; a new segmenter builds this table on its first scan, where one sine and cosine per pixel
  // instead of three was most of that scan's extra time).
  std::vector<double> theta_e(size_t(std::max(width, 0)));
  std::vector<Eigen::Vector3d> e(theta_e.size());
  for (int v = 0; v < width; ++v) {
    theta_e[size_t(v)] = 2.0 * M_PI - v * 2.0 * M_PI / width;
    e[size_t(v)] = Eigen::Vector3d(std::cos(theta_e[size_t(v)]), std::sin(theta_e[size_t(v)]), 0.0);
  }
  for (int u = 0; u < lut.height; ++u) {
    const double phi = beams.altitude_deg[u] * M_PI / 180.0;
    const double theta_a = -beams.azimuth_deg[u] * M_PI / 180.0;
    const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);  // (per beam)
    for (int v = 0; v < width; ++v) {
      const double theta = theta_e[size_t(v)] + theta_a;
      double ct = std::cos(theta), st = std::sin(theta);
#if defined(__GNUC__) && defined(__x86_64__)
      // (each taken into a register as it is: the compiler otherwise reads the two results sincos stores as one
      // 16-byte load, which cannot be forwarded from the two 8-byte stores and waited for them on every pixel)
      asm("" : "+x"(ct), "+x"(st));
#endif
      // p(r) = (r - n) * d + n * e  =  r * d + (n * e - n * d)
      const Eigen::Vector3d d(ct * cos_phi, st * cos_phi, sin_phi);
      const Eigen::Vector3d& ev = e[size_t(v)];
      const Eigen::Vector3d dir = R * d;                          // per mm of range
      const Eigen::Vector3d off = R * (n_mm * ev - n_mm * d) + t;  // mm
      const size_t i = size_t(u) * width + v;
      lut.direction.row(i) = (dir * 1e-3).cast<float>().transpose();
      lut.offset.row(i) = (off * 1e-3).cast<float>().transpose();
    }
  }
  return lut;
}

void scan_to_xyz(const Scan& scan, const XyzLut& lut, std::vector<Eigen::Vector3f>& out) {
  out.resize(size_t(scan.height) * scan.width);
  for (int u = 0; u < scan.height; ++u) {
    for (int c = 0; c < scan.width; ++c) {
      const int mid = scan.measurement_id.empty() ? c : scan.measurement_id[c];
      out[size_t(u) * scan.width + c] = lut_point(lut, u, mid, scan.range(u, c));
    }
  }
}

}  // namespace fploc
