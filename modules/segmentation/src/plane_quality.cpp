// Plane quality: inliers, returns beyond the plane, rms, and the 1-sigma of its normal and distance.
#include <algorithm>
#include <cmath>

#include "fploc/segmentation/segmenter.h"
#include "compact_kernels.h"
#include "plane_kernels.h"
#include "plane_math.h"

namespace fploc::seg {

void Segmenter::quality(const Candidates& c, Plane& pl) const {
  const Eigen::Vector3f n = pl.coeffs.head<3>().cast<float>();
  const float d = float(pl.coeffs[3]);
  const float thr = float(cfg_.inlier_threshold_m);
  const float beyond_thr = 2 * thr;
  // Moments of the inliers relative to the first inlier (numerics), float sums over blocks of 256 points
  // added up in double (plane_kernels.h); the NaN padding of the candidates counts nowhere.
  size_t first = 0;
  while (first < c.n && !(std::abs(n.dot(c.point(first)) + d) < thr)) ++first;
  const Eigen::Vector3f reff = first < c.n ? c.point(first) : Eigen::Vector3f::Zero();
  double S[9], r2 = 0;
  int cnt = 0, beyond = 0;
  const float ref3[3] = {reff.x(), reff.y(), reff.z()};
  const float plf[4] = {n.x(), n.y(), n.z(), d};
  const ck::BoxRange br(c.box.data(), c.box_stride, c.box_r, plf);
  kern::inlier_moments(c.x.data(), c.y.data(), c.z.data(), (c.n + 3) & ~size_t(3), {n.x(), n.y(), n.z(), d}, thr, beyond_thr,
                       ref3, S, r2, cnt, beyond, c.n, c.has_boxes() ? &br : nullptr);
  const detail::Moments m = detail::Moments::from_inliers(S, cnt);
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
