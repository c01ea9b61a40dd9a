// Plane quality: inliers, returns beyond the plane, rms, and the 1-sigma of its normal and distance.
#include <algorithm>
#include <cmath>

#include "fploc/segmentation/segmenter.h"
#include "plane_math.h"
#include "simd4.h"

namespace fploc::seg {

void Segmenter::quality(const Candidates& c, Plane& pl) const {
  using namespace simd;
  const Eigen::Vector3f n = pl.coeffs.head<3>().cast<float>();
  const float d = float(pl.coeffs[3]);
  const float thr = float(cfg_.inlier_threshold_m);
  const float beyond_thr = 2 * thr;
  // Moments of the inliers relative to the first inlier (numerics), four lanes, float sums over blocks of
  // 256 points added up in double; the NaN padding of the candidates counts nowhere.
  size_t first = 0;
  while (first < c.n && !(std::abs(n.dot(c.point(first)) + d) < thr)) ++first;
  const Eigen::Vector3f reff = first < c.n ? c.point(first) : Eigen::Vector3f::Zero();
  const v4f nx = splat(n.x()), ny = splat(n.y()), nz = splat(n.z()), dv = splat(d), zero = splat(0.f);
  const v4f tv = splat(thr), bv = splat(-beyond_thr), rx = splat(reff.x()), ry = splat(reff.y()), rz = splat(reff.z());
  double S[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, r2 = 0;
  v4i cntv = splati(0), beyondv = splati(0);
  const size_t np = (c.n + 3) & ~size_t(3);
  for (size_t j0 = 0; j0 < np; j0 += 256) {
    v4f sx = zero, sy = zero, sz = zero, sxx = zero, sxy = zero, sxz = zero, syy = zero, syz = zero, szz = zero,
        sr2 = zero;
    for (size_t j = j0, je = std::min(np, j0 + 256); j < je; j += 4) {
      const v4f x = load(c.x.data() + j), y = load(c.y.data() + j), z = load(c.z.data() + j);
      const v4f r = nx * x + ny * y + nz * z + dv;
      beyondv -= (r < bv);
      const v4i in = abs(r) < tv;
      cntv -= in;
      const v4f qx = in ? x - rx : zero, qy = in ? y - ry : zero, qz = in ? z - rz : zero, qr = in ? r : zero;
      sx += qx; sy += qy; sz += qz;
      sxx += qx * qx; sxy += qx * qy; sxz += qx * qz; syy += qy * qy; syz += qy * qz; szz += qz * qz;
      sr2 += qr * qr;
    }
    const v4f all[9] = {sx, sy, sz, sxx, sxy, sxz, syy, syz, szz};
    for (int q = 0; q < 9; ++q) S[q] += double(hsum(all[q]));
    r2 += double(hsum(sr2));
  }
  const int cnt = hsum(cntv), beyond = hsum(beyondv);
  const double sx = S[0], sy = S[1], sz = S[2], sxx = S[3], sxy = S[4], sxz = S[5], syy = S[6], syz = S[7], szz = S[8];
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
