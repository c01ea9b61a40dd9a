#include "fploc/floorplan/plan.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fploc {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// Angle of v in [a0, a0 + 2pi).
double angle_from(double ang, double a0) {
  double d = std::fmod(ang - a0, kTwoPi);
  if (d < 0) d += kTwoPi;
  return a0 + d;
}

bool arc_contains_angle(const Element& e, double ang) { return angle_from(ang, e.a0) <= e.a1; }

Eigen::Vector2d arc_point(const Element& e, double ang) { return e.c + e.r * Eigen::Vector2d(std::cos(ang), std::sin(ang)); }

// Squared distance from a point to a segment.
double point_segment_sq(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  double t = l2 > 0 ? (p - a).dot(ab) / l2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return (a + t * ab - p).squaredNorm();
}


bool segments_intersect(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                        const Eigen::Vector2d& q2) {
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
  const double d1 = cross(q2 - q1, p1 - q1), d2 = cross(q2 - q1, p2 - q1);
  const double d3 = cross(p2 - p1, q1 - p1), d4 = cross(p2 - p1, q2 - p1);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto on = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, double d) {
    return d == 0 && std::min(a.x(), b.x()) <= c.x() && c.x() <= std::max(a.x(), b.x()) &&
           std::min(a.y(), b.y()) <= c.y() && c.y() <= std::max(a.y(), b.y());
  };
  return on(q1, q2, p1, d1) || on(q1, q2, p2, d2) || on(p1, p2, q1, d3) || on(p1, p2, q2, d4);
}

bool box_contains(const Box2& b, const Eigen::Vector2d& p) {
  return p.x() >= b.min.x() && p.x() <= b.max.x() && p.y() >= b.min.y() && p.y() <= b.max.y();
}

// Distance from a point to the box (0 inside).
double point_box(const Eigen::Vector2d& p, const Box2& b) {
  const double dx = std::max({b.min.x() - p.x(), 0.0, p.x() - b.max.x()});
  const double dy = std::max({b.min.y() - p.y(), 0.0, p.y() - b.max.y()});
  return std::sqrt(dx * dx + dy * dy);  // (hypot is ~5x slower; coordinates are far from overflow)
}

// Largest distance from the point to the box.
double point_box_far(const Eigen::Vector2d& p, const Box2& b) {
  const double dx = std::max(std::abs(p.x() - b.min.x()), std::abs(p.x() - b.max.x()));
  const double dy = std::max(std::abs(p.y() - b.min.y()), std::abs(p.y() - b.max.y()));
  return std::sqrt(dx * dx + dy * dy);
}

std::array<Eigen::Vector2d, 4> corners(const Box2& b) {
  return {Eigen::Vector2d(b.min.x(), b.min.y()), Eigen::Vector2d(b.max.x(), b.min.y()),
          Eigen::Vector2d(b.max.x(), b.max.y()), Eigen::Vector2d(b.min.x(), b.max.y())};
}

}  // namespace

Element Element::segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, int layer) {
  Element e;
  e.kind = ElementKind::kSegment;
  e.a = a;
  e.b = b;
  e.layer = layer;
  return e;
}

Element Element::circle(const Eigen::Vector2d& c, double r, int layer) {
  Element e;
  e.kind = ElementKind::kCircle;
  e.c = c;
  e.r = r;
  e.a0 = 0;
  e.a1 = kTwoPi;
  e.layer = layer;
  return e;
}

Element Element::arc(const Eigen::Vector2d& c, double r, double a0, double a1, int layer) {
  Element e;
  e.kind = ElementKind::kArc;
  e.c = c;
  e.r = r;
  e.a0 = std::fmod(a0, kTwoPi);
  if (e.a0 < 0) e.a0 += kTwoPi;
  double sweep = std::fmod(a1 - a0, kTwoPi);
  if (sweep <= 0) sweep += kTwoPi;
  e.a1 = e.a0 + sweep;
  e.a = arc_point(e, e.a0);
  e.b = arc_point(e, e.a1);
  e.layer = layer;
  return e;
}

ClosestPoint closest_point(const Element& e, const Eigen::Vector2d& p) {
  ClosestPoint out;
  switch (e.kind) {
    case ElementKind::kSegment: {
      const Eigen::Vector2d ab = e.b - e.a;
      const double l2 = ab.squaredNorm();
      double t = l2 > 0 ? (p - e.a).dot(ab) / l2 : 0.0;
      t = std::clamp(t, 0.0, 1.0);
      out.point = e.a + t * ab;
      break;
    }
    case ElementKind::kCircle: {
      const Eigen::Vector2d d = p - e.c;
      const double n = d.norm();
      out.point = n > 0 ? Eigen::Vector2d(e.c + d * (e.r / n)) : Eigen::Vector2d(e.c + Eigen::Vector2d(e.r, 0));
      break;
    }
    case ElementKind::kArc: {
      const Eigen::Vector2d d = p - e.c;
      const double ang = std::atan2(d.y(), d.x());
      if (d.squaredNorm() > 0 && arc_contains_angle(e, ang)) {
        out.point = e.c + d * (e.r / d.norm());
      } else {
        const Eigen::Vector2d pa = arc_point(e, e.a0), pb = arc_point(e, e.a1);
        out.point = (pa - p).squaredNorm() <= (pb - p).squaredNorm() ? pa : pb;
      }
      break;
    }
  }
  out.distance = (out.point - p).norm();
  return out;
}

void Box2::extend(const Eigen::Vector2d& p) {
  if (empty()) {
    min = max = p;
  } else {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
}

void Box2::extend(const Box2& b) {
  if (b.empty()) return;
  extend(b.min);
  extend(b.max);
}

Box2 bounds(const Element& e) {
  Box2 b;
  b.min = {1, 1};
  b.max = {0, 0};  // empty
  switch (e.kind) {
    case ElementKind::kSegment:
      b.extend(e.a);
      b.extend(e.b);
      break;
    case ElementKind::kCircle:
      b.extend(e.c - Eigen::Vector2d(e.r, e.r));
      b.extend(e.c + Eigen::Vector2d(e.r, e.r));
      break;
    case ElementKind::kArc:
      b.extend(arc_point(e, e.a0));
      b.extend(arc_point(e, e.a1));
      for (int k = 0; k < 8; ++k) {
        const double ang = k * M_PI / 2;
        if (arc_contains_angle(e, ang)) b.extend(arc_point(e, ang));
      }
      break;
  }
  return b;
}

double min_distance(const Element& e, const Box2& box) {
  switch (e.kind) {
    case ElementKind::kSegment: {
      if (box_contains(box, e.a) || box_contains(box, e.b)) return 0.0;
      const auto c = corners(box);
      for (int i = 0; i < 4; ++i)
        if (segments_intersect(e.a, e.b, c[i], c[(i + 1) % 4])) return 0.0;
      double d = std::min(point_box(e.a, box), point_box(e.b, box));
      double d2 = d * d;
      for (int i = 0; i < 4; ++i) d2 = std::min(d2, point_segment_sq(c[i], e.a, e.b));
      return std::sqrt(d2);
    }
    case ElementKind::kCircle: {
      const double near = point_box(e.c, box), far = point_box_far(e.c, box);
      if (near <= e.r && e.r <= far) return 0.0;
      return e.r < near ? near - e.r : e.r - far;
    }
    case ElementKind::kArc: {
      // Lower bound: distance to the full circle, or to the end points if tighter is not provable.
      const double near = point_box(e.c, box), far = point_box_far(e.c, box);
      double circle_lb = (near <= e.r && e.r <= far) ? 0.0 : (e.r < near ? near - e.r : e.r - far);
      const double ends = std::min(point_box(arc_point(e, e.a0), box), point_box(arc_point(e, e.a1), box));
      // The arc's points are a subset of the circle: circle_lb is valid; ends is an upper bound on the
      // minimum only, so the valid lower bound is circle_lb. Tighten with the arc's bounding box.
      const Box2 ab = bounds(e);
      const double dx = std::max({ab.min.x() - box.max.x(), 0.0, box.min.x() - ab.max.x()});
      const double dy = std::max({ab.min.y() - box.max.y(), 0.0, box.min.y() - ab.max.y()});
      (void)ends;
      return std::max(circle_lb, std::hypot(dx, dy));
    }
  }
  return 0.0;
}

double max_distance(const Element& e, const Box2& box) {
  // The distance to a convex set... elements are not convex in general, but the function
  // f(p) = dist(p, segment) is convex, so its maximum over the box is at a corner. For circles and
  // arcs use dist(p, e) <= dist(p, c) + r bounded at the far corner (valid, conservative for arcs).
  const auto c = corners(box);
  double m = 0.0;
  switch (e.kind) {
    case ElementKind::kSegment:
      for (const auto& p : c) m = std::max(m, point_segment_sq(p, e.a, e.b));
      return std::sqrt(m);
    case ElementKind::kCircle:
    case ElementKind::kArc: {
      // dist(p, circle) = |‖p - c‖ - r| <= max(far - r, r - near) ; for arcs, dist(p, arc) <= max over the
      // box of the distance to any single fixed arc point; use the arc's start point (convex in p).
      if (e.kind == ElementKind::kCircle) {
        const double near = point_box(e.c, box), far = point_box_far(e.c, box);
        return std::max(far - e.r, e.r - near);
      }
      const Eigen::Vector2d s = arc_point(e, e.a0);
      for (const auto& p : c) m = std::max(m, (p - s).norm());
      return m;
    }
  }
  return m;
}

Box2 FloorPlan::bounds() const {
  Box2 b;
  b.min = {1, 1};
  b.max = {0, 0};
  for (const auto& e : elements) b.extend(fploc::bounds(e));
  return b;
}

int FloorPlan::layer_index(const std::string& name) {
  for (size_t i = 0; i < layers.size(); ++i)
    if (layers[i] == name) return int(i);
  layers.push_back(name);
  return int(layers.size()) - 1;
}

int nearest_element_brute_force(const FloorPlan& plan, const Eigen::Vector2d& p, double* dist) {
  int best = -1;
  double bd = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    const double d = distance(plan.elements[i], p);
    if (d < bd) {
      bd = d;
      best = int(i);
    }
  }
  if (dist) *dist = bd;
  return best;
}

}  // namespace fploc
