#include "fploc/core/xyz.h"

#include <cmath>
#include <limits>

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
  for (int u = 0; u < lut.height; ++u) {
    const double phi = beams.altitude_deg[u] * M_PI / 180.0;
    const double theta_a = -beams.azimuth_deg[u] * M_PI / 180.0;
    for (int v = 0; v < width; ++v) {
      const double theta_e = 2.0 * M_PI - v * 2.0 * M_PI / width;
      // p(r) = (r - n) * d + n * e  =  r * d + (n * e - n * d)
      const Eigen::Vector3d d(std::cos(theta_e + theta_a) * std::cos(phi),
                              std::sin(theta_e + theta_a) * std::cos(phi), std::sin(phi));
      const Eigen::Vector3d e(std::cos(theta_e), std::sin(theta_e), 0.0);
      const Eigen::Vector3d dir = R * d;                          // per mm of range
      const Eigen::Vector3d off = R * (n_mm * e - n_mm * d) + t;  // mm
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
