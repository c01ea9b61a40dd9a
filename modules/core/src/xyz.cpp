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
  // The encoder angle and its direction per column, the same for every beam: computed once; a pixel's angle
  // theta_e + theta_a from them and the beam's by the angle sums, no sine or cosine per pixel (a new segmenter
  // builds this table on its first scan: its 65,536 sincos calls were most of that scan's extra time).
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
    const double cos_a = std::cos(theta_a), sin_a = std::sin(theta_a);
    for (int v = 0; v < width; ++v) {
      // cos / sin of theta_e + theta_a by the angle sums, in double: within a few 1e-16 of std::cos / std::sin
      // of the sum, which the floats below do not see except where a value lies that near a float's rounding
      // edge (3 of 25.4 million table values over 40 random beam sets and widths; none of the OS-1 tables tested)
      const Eigen::Vector3d& ev = e[size_t(v)];
      const double ct = ev.x() * cos_a - ev.y() * sin_a, st = ev.y() * cos_a + ev.x() * sin_a;
      // p(r) = (r - n) * d + n * e  =  r * d + (n * e - n * d)
      const Eigen::Vector3d d(ct * cos_phi, st * cos_phi, sin_phi);
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
