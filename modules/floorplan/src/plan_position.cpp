#include "fploc/floorplan/plan_position.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fploc {
namespace {

double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

// Whether the ray p + t d, 0 <= t <= len (|d| = 1), meets the element.
bool ray_meets(const Element& e, const Eigen::Vector2d& p, const Eigen::Vector2d& d, double len) {
  if (e.kind == ElementKind::kSegment) {
    const Eigen::Vector2d s = e.b - e.a, w = e.a - p;
    const double den = cross(d, s);
    if (std::abs(den) < 1e-12) return false;  // parallel (a ray along a wall meets the walls at its ends)
    const double t = cross(w, s) / den, u = cross(w, d) / den;
    return t >= 0 && t <= len && u >= 0 && u <= 1;
  }
  // Circle or arc: |p + t d - c| = r.
  const Eigen::Vector2d f = p - e.c;
  const double b = f.dot(d), c = f.squaredNorm() - e.r * e.r, disc = b * b - c;
  if (disc < 0) return false;
  const double sq = std::sqrt(disc);
  for (const double t : {-b - sq, -b + sq}) {
    if (t < 0 || t > len) continue;
    if (e.kind == ElementKind::kCircle) return true;
    const Eigen::Vector2d q = f + t * d;
    double a = std::fmod(std::atan2(q.y(), q.x()) - e.a0, 2 * M_PI);
    if (a < 0) a += 2 * M_PI;
    if (e.a0 + a <= e.a1) return true;
  }
  return false;
}

}  // namespace

PlanPosition locate_in_plan(const FloorPlan& plan, const Eigen::Vector2d& p, int directions) {
  PlanPosition r;
  r.extent = plan.bounds();
  if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || r.extent.empty()) {
    r.outside_m = std::numeric_limits<double>::infinity();
    return r;
  }
  const Box2& b = r.extent;
  r.outside_m = std::hypot(std::max({b.min.x() - p.x(), 0.0, p.x() - b.max.x()}),
                           std::max({b.min.y() - p.y(), 0.0, p.y() - b.max.y()}));
  if (r.outside_m > 0) return r;
  const double len = std::hypot(b.size().x(), b.size().y()) + 1;
  r.directions = std::max(1, directions);
  for (int k = 0; k < r.directions; ++k) {
    const double a = 2 * M_PI * k / r.directions;
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    for (const auto& e : plan.elements)
      if (ray_meets(e, p, d, len)) {
        ++r.hits;
        break;
      }
  }
  return r;
}

}  // namespace fploc
