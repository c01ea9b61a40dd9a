// Small 2D segment geometry shared by the simulator's world edits and the plan-change detector.
#pragma once
#include <Eigen/Core>
#include <cmath>

namespace fploc {

// z of the 3D cross product of two plane vectors.
inline double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Does segment p-q cross segment a-b? Parallel segments never do. The crossing must lie strictly inside
// p-q, at least `end_margin` (a fraction of p-q's length) from either end; anywhere on a-b.
inline bool segments_cross(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& a,
                           const Eigen::Vector2d& b, double end_margin = 0.0) {
  const Eigen::Vector2d r = q - p, s = b - a;
  const double den = cross2(r, s);
  if (std::abs(den) < 1e-12) return false;
  const double t = cross2(a - p, s) / den, u = cross2(a - p, r) / den;
  return t > end_margin && t < 1 - end_margin && u >= 0 && u <= 1;
}

}  // namespace fploc
