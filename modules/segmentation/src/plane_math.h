// Small numerical helpers shared by the segmenter's plane fits and plane quality (internal header).
#pragma once
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif
#include <algorithm>
#include <cmath>
#include <vector>

namespace fploc::seg::detail {

// Orthonormal basis (e1, e2) of the plane orthogonal to `u`.
inline void basis(const Eigen::Vector3d& u, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const Eigen::Vector3d a = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (a - a.dot(u) * u).normalized();
  e2 = u.cross(e1);
}

// Weighted least-squares plane through accumulated moments; normal oriented against `up`.
struct Moments {
  double w = 0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
  // From the point kernels' sums (plane_kernels.h): tukey_moments' S = w, w x, w y, w z, w xx, w xy, w xz, w yy,
  // w yz, w zz; inlier_moments' S = x, y, z, xx, xy, xz, yy, yz, zz of `count` points weighing 1.
  static Moments from_weighted(const double S[10]) {
    Moments m;
    m.w = S[0];
    m.s << S[1], S[2], S[3];
    m.ss << S[4], S[5], S[6], S[5], S[7], S[8], S[6], S[8], S[9];
    return m;
  }
  static Moments from_inliers(const double S[9], int count) {
    Moments m;
    m.w = count;
    m.s << S[0], S[1], S[2];
    m.ss << S[3], S[4], S[5], S[4], S[6], S[7], S[5], S[7], S[8];
    return m;
  }
  void add(const Eigen::Vector3d& p, double wi) {
    w += wi;
    s += wi * p;
    ss.noalias() += wi * p * p.transpose();
  }
  // add(p, 1.0) (the same sums bit for bit: a product with 1 is exact and p_i p_j = p_j p_i), the six distinct
  // products once.
  void add1(const Eigen::Vector3d& p) {
    w += 1.0;
    s += p;
    const double xx = p.x() * p.x(), xy = p.y() * p.x(), xz = p.z() * p.x(), yy = p.y() * p.y(), yz = p.z() * p.y(),
                 zz = p.z() * p.z();
    ss(0, 0) += xx;
    ss(1, 0) += xy;
    ss(2, 0) += xz;
    ss(0, 1) += xy;
    ss(1, 1) += yy;
    ss(2, 1) += yz;
    ss(0, 2) += xz;
    ss(1, 2) += yz;
    ss(2, 2) += zz;
  }
  // add1 of the points (x[j], y[j], z[j]) in float, j < m, in order, on empty moments (the same sums bit for bit:
  // each sum takes the same terms in the same order; w counts them, exactly; the three mirrored products of ss
  // are summed once). The sums stay in registers, not in the moments' members.
  static Moments of_points(const float* x, const float* y, const float* z, size_t m) {
    double S[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    for (size_t j = 0; j < m; ++j) {
      const double px = x[j], py = y[j], pz = z[j];
      S[0] += px;
      S[1] += py;
      S[2] += pz;
      S[3] += px * px;
      S[4] += py * px;
      S[5] += pz * px;
      S[6] += py * py;
      S[7] += pz * py;
      S[8] += pz * pz;
    }
    return from_inliers(S, int(m));
  }
  bool plane(const Eigen::Vector3d& ref, const Eigen::Vector3d& up, Eigen::Vector4d& out,
             Eigen::Vector3d* eigenvalues = nullptr) const {
    if (w <= 0) return false;
    const Eigen::Vector3d c = s / w;
    const Eigen::Matrix3d cov = ss / w - c * c.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(cov);
    Eigen::Vector3d n = es.eigenvectors().col(0);
    if (!n.allFinite()) return false;
    if (n.dot(up) > 0) n = -n;
    const Eigen::Vector3d cw = c + ref;
    out << n, -n.dot(cw);
    if (eigenvalues) *eigenvalues = es.eigenvalues() * w;
    return true;
  }
};

// max(0, q) without a branch (std::max compiled to one here and mispredicted at every band edge); same
// value as std::max(0.f, q) for every q, NaN included (maxss returns its second operand then).
inline float max0(float q) {
#if defined(__SSE__)
  return _mm_cvtss_f32(_mm_max_ss(_mm_set_ss(q), _mm_setzero_ps()));
#else
  return std::max(0.f, q);
#endif
}

inline double median_inplace(std::vector<float>& v) {
  if (v.empty()) return 0.0;
  auto mid = v.begin() + v.size() / 2;
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace fploc::seg::detail
