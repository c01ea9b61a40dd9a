#include "synthetic.h"

#include <cmath>
#include <limits>
#include <random>

namespace fploc::testing {

FloorPlan room_with_pillars() {
  FloorPlan p;
  auto seg = [&](double x1, double y1, double x2, double y2) { p.elements.push_back(Element::segment({x1, y1}, {x2, y2})); };
  // Outer walls with a 1 m door on the south wall (x 4..5) and on the north wall (x 15..16).
  seg(0, 0, 4, 0);
  seg(5, 0, 20, 0);
  seg(20, 0, 20, 10);
  seg(20, 10, 16, 10);
  seg(15, 10, 0, 10);
  seg(0, 10, 0, 0);
  // Window recess on the east wall (a notch).
  seg(20, 4, 20.3, 4);
  seg(20.3, 4, 20.3, 6);
  seg(20.3, 6, 20, 6);
  // Square pillar 0.6 m at (7, 5).
  seg(6.7, 4.7, 7.3, 4.7);
  seg(7.3, 4.7, 7.3, 5.3);
  seg(7.3, 5.3, 6.7, 5.3);
  seg(6.7, 5.3, 6.7, 4.7);
  // Round pillars.
  p.elements.push_back(Element::circle({13, 3.5}, 0.3));
  p.elements.push_back(Element::circle({13, 6.5}, 0.3));
  p.source = "synthetic-room";
  return p;
}

FloorPlan endless_corridor() {
  FloorPlan p;
  p.elements.push_back(Element::segment({-100, 0}, {100, 0}));
  p.elements.push_back(Element::segment({-100, 2}, {100, 2}));
  p.source = "synthetic-endless-corridor";
  return p;
}

FloorPlan corridor_loop() {
  FloorPlan p;
  auto seg = [&](double x1, double y1, double x2, double y2) { p.elements.push_back(Element::segment({x1, y1}, {x2, y2})); };
  // Outer square 24 x 24 with a bend, inner block leaving 2 m wide corridors.
  seg(0, 0, 24, 0);
  seg(24, 0, 24, 24);
  seg(24, 24, 0, 24);
  seg(0, 24, 0, 0);
  seg(2, 2, 22, 2);
  seg(22, 2, 22, 22);
  seg(22, 22, 2, 22);
  seg(2, 22, 2, 2);
  p.source = "synthetic-corridor";
  return p;
}

namespace {

// Ray (o + t d, t > 0) against an element: smallest t or +inf.
double ray_hit(const Element& e, const Eigen::Vector2d& o, const Eigen::Vector2d& d) {
  const double inf = std::numeric_limits<double>::infinity();
  if (e.kind == ElementKind::kSegment) {
    const Eigen::Vector2d s = e.b - e.a;
    const double den = d.x() * s.y() - d.y() * s.x();
    if (std::abs(den) < 1e-12) return inf;
    const Eigen::Vector2d w = e.a - o;
    const double t = (w.x() * s.y() - w.y() * s.x()) / den;
    const double u = (w.x() * d.y() - w.y() * d.x()) / den;
    return (t > 1e-9 && u >= 0 && u <= 1) ? t : inf;
  }
  const Eigen::Vector2d w = o - e.c;
  const double b = w.dot(d), c = w.squaredNorm() - e.r * e.r;
  const double disc = b * b - c;
  if (disc < 0) return inf;
  for (double t : {-b - std::sqrt(disc), -b + std::sqrt(disc)}) {
    if (t <= 1e-9) continue;
    if (e.kind == ElementKind::kArc) {
      const Eigen::Vector2d h = o + t * d - e.c;
      double rel = std::fmod(std::atan2(h.y(), h.x()) - e.a0, 2 * M_PI);
      if (rel < 0) rel += 2 * M_PI;
      if (e.a0 + rel > e.a1) continue;
    }
    return t;
  }
  return inf;
}

}  // namespace

FeatureFrame synth_frame(const FloorPlan& plan, const Pose2& pose, const SynthOptions& o, int64_t utime) {
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  FeatureFrame f;
  f.utime = utime;
  f.z = 1.5;
  std::vector<int> hit_element;
  for (int i = 0; i < o.beams; ++i) {
    const double a = 2 * M_PI * i / o.beams;  // sensor-frame bearing
    const double tb = o.sweep_s * i / o.beams;
    const Pose2 pb = tb > 0 ? compose(pose, matcher::exp_twist(o.sweep_twist, tb)) : pose;
    const Eigen::Vector2d origin(pb.x, pb.y);
    const Eigen::Vector2d dir(std::cos(a + pb.yaw), std::sin(a + pb.yaw));
    double best = std::numeric_limits<double>::infinity();
    int be = -1;
    for (size_t k = 0; k < plan.elements.size(); ++k) {
      const double t = ray_hit(plan.elements[k], origin, dir);
      if (t < best) {
        best = t;
        be = int(k);
      }
    }
    if (be < 0 || best > o.max_range) continue;
    const double range = best + o.noise_sigma * noise(rng);
    Feature2 fp;
    fp.p = range * Eigen::Vector2d(std::cos(a), std::sin(a));
    fp.kind = FeatureKind::kSurface;
    fp.t = float(tb);
    f.points.push_back(fp);
    hit_element.push_back(plan.elements[size_t(be)].kind == ElementKind::kSegment ? be : -1);
  }
  // Groups: runs of >= 5 consecutive hits on one segment; run boundaries are corners.
  int next_group = 0;
  for (size_t i = 0; i < f.points.size();) {
    size_t j = i;
    while (j < f.points.size() && hit_element[j] == hit_element[i]) ++j;
    if (o.groups && hit_element[i] >= 0 && j - i >= 5) {
      for (size_t k = i; k < j; ++k) f.points[k].group = next_group;
      ++next_group;
    }
    f.points[i].kind = FeatureKind::kCorner;
    i = j;
  }
  const int nclutter = int(std::lround(o.clutter_fraction * double(f.points.size())));
  for (int i = 0; i < nclutter; ++i) {
    const double a = 2 * M_PI * uni(rng), r = 0.5 + (o.clutter_radius - 0.5) * uni(rng);
    Feature2 fp;
    fp.p = r * Eigen::Vector2d(std::cos(a), std::sin(a));
    fp.kind = FeatureKind::kSurface;
    f.points.push_back(fp);
  }
  return f;
}

FeatureFrame random_frame(int n, double radius, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-radius, radius);
  FeatureFrame f;
  for (int i = 0; i < n; ++i) {
    Feature2 fp;
    fp.p = {uni(rng), uni(rng)};
    f.points.push_back(fp);
  }
  return f;
}

}  // namespace fploc::testing
