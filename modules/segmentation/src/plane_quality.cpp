// Plane quality: inliers, returns beyond the plane, rms, and the 1-sigma of its normal and distance.
#include <cmath>

#include "fploc/segmentation/segmenter.h"
#include "plane_math.h"

namespace fploc::seg {

void Segmenter::quality(const Candidates& c, Plane& pl) const {
  const Eigen::Vector3f n = pl.coeffs.head<3>().cast<float>();
  const float d = float(pl.coeffs[3]);
  const float thr = float(cfg_.inlier_threshold_m);
  double r2 = 0;
  int cnt = 0, beyond = 0;
  const float beyond_thr = 2 * thr;
  Eigen::Vector3f reff = Eigen::Vector3f::Zero();
  bool have_ref = false;
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  for (size_t i = 0; i < c.p.size(); ++i) {
    const float r = n.dot(c.p[i]) + d;
    if (r < -beyond_thr) ++beyond;
    if (std::abs(r) >= thr) continue;
    if (!have_ref) {
      reff = c.p[i];
      have_ref = true;
    }
    const double x = c.p[i].x() - reff.x(), y = c.p[i].y() - reff.y(), z = c.p[i].z() - reff.z();
    sx += x; sy += y; sz += z;
    sxx += x * x; sxy += x * y; sxz += x * z; syy += y * y; syz += y * z; szz += z * z;
    r2 += double(r) * r;
    ++cnt;
  }
  detail::Moments m;
  m.w = cnt;
  m.s << sx, sy, sz;
  m.ss << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  const Eigen::Vector3d ref = reff.cast<double>();
  pl.inliers = cnt;
  pl.beyond = beyond;
  pl.rms_m = cnt ? std::sqrt(r2 / cnt) : 0.0;
  if (cnt < 3) return;
  Eigen::Vector4d tmp;
  Eigen::Vector3d ev;
  m.plane(ref, -pl.coeffs.head<3>(), tmp, &ev);
  // Normal uncertainty ~ sigma / sqrt(smallest in-plane scatter); distance ~ sigma / sqrt(N) plus the lever
  // arm from the inlier centroid to the sensor.
  const double sig = std::max(pl.rms_m, 1e-4);
  pl.tilt_sigma = sig / std::sqrt(std::max(ev[1], 1e-9));
  const Eigen::Vector3d cen = m.s / m.w + ref;
  const Eigen::Vector3d nn = pl.coeffs.head<3>();
  const double lever = (cen - nn.dot(cen) * nn).norm();
  pl.d_sigma = std::hypot(sig / std::sqrt(double(cnt)), lever * pl.tilt_sigma);
}

}  // namespace fploc::seg
