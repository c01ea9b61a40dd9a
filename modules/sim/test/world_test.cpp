// Ray caster against independent brute-force analytic geometry.
#include <gtest/gtest.h>
#include <Eigen/LU>

#include <cmath>
#include <limits>

#include "fploc/core/rng.h"
#include "fploc/sim/world.h"

using namespace fploc;
using namespace fploc::sim;
using V2 = Eigen::Vector2d;
using V3 = Eigen::Vector3d;

namespace {

FloorPlan box_room(double w, double h) {
  FloorPlan p;
  const int l = p.layer_index("walls");
  p.elements.push_back(Element::segment(V2(0, 0), V2(w, 0), l));
  p.elements.push_back(Element::segment(V2(w, 0), V2(w, h), l));
  p.elements.push_back(Element::segment(V2(w, h), V2(0, h), l));
  p.elements.push_back(Element::segment(V2(0, h), V2(0, 0), l));
  return p;
}

// Independent reference: smallest positive t over every primitive, no acceleration structure.
double reference_t(const FloorPlan& p, double ceil_h, const V3& o, const V3& d, int* elem) {
  double best = std::numeric_limits<double>::infinity();
  *elem = -2;
  if (d.z() < 0) best = -o.z() / d.z(), *elem = -1;
  if (d.z() > 0) best = (ceil_h - o.z()) / d.z(), *elem = -1;
  for (size_t i = 0; i < p.elements.size(); ++i) {
    const Element& e = p.elements[i];
    // Sample-free: solve in 2D.
    if (e.kind == ElementKind::kSegment) {
      const V2 u = e.b - e.a;
      Eigen::Matrix2d M;
      M << d.x(), -u.x(), d.y(), -u.y();
      if (std::abs(M.determinant()) < 1e-12) continue;
      const V2 ts = M.inverse() * (e.a - o.head<2>());
      if (ts[0] > 1e-9 && ts[1] >= 0 && ts[1] <= 1 && ts[0] < best) {
        const double z = o.z() + ts[0] * d.z();
        if (z >= 0 && z <= ceil_h) best = ts[0], *elem = int(i);
      }
    } else if (e.kind == ElementKind::kCircle) {
      // |o + t d - c|^2 = r^2 in 2D.
      const V2 f = o.head<2>() - e.c, d2 = d.head<2>();
      const double a = d2.squaredNorm(), b = 2 * f.dot(d2), c = f.squaredNorm() - e.r * e.r;
      const double disc = b * b - 4 * a * c;
      if (disc < 0 || a < 1e-15) continue;
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      if (t > 1e-9 && t < best) {
        const double z = o.z() + t * d.z();
        if (z >= 0 && z <= ceil_h) best = t, *elem = int(i);
      }
    }
  }
  return best;
}

}  // namespace

TEST(World, AxisRays) {
  WorldConfig cfg;
  cfg.ceiling_height_m = 3.0;
  World w(box_room(10, 8), cfg);
  const V3 o(4, 3, 1.5);
  Hit h = w.cast(o, V3(1, 0, 0), 100);
  EXPECT_EQ(h.label, Label::kWall);
  EXPECT_EQ(h.element, 1);
  EXPECT_NEAR(h.t, 6.0, 1e-9);
  h = w.cast(o, V3(-1, 0, 0), 100);
  EXPECT_EQ(h.element, 3);
  EXPECT_NEAR(h.t, 4.0, 1e-9);
  h = w.cast(o, V3(0, 0, 1), 100);
  EXPECT_EQ(h.label, Label::kCeiling);
  EXPECT_NEAR(h.t, 1.5, 1e-9);
  h = w.cast(o, V3(0, 1, -1).normalized(), 100);
  EXPECT_EQ(h.label, Label::kFloor);
  EXPECT_NEAR(h.t, 1.5 * std::sqrt(2.0), 1e-9);
  // Max range.
  h = w.cast(o, V3(1, 0, 0), 5.0);
  EXPECT_EQ(h.label, Label::kNone);
}

TEST(World, RandomRaysMatchBruteForce) {
  FloorPlan p = box_room(20, 15);
  const int l = p.layer_index("walls");
  // Interior walls at odd angles and pillars.
  p.elements.push_back(Element::segment(V2(3, 2), V2(9, 7.5), l));
  p.elements.push_back(Element::segment(V2(12, 12), V2(17.3, 4.1), l));
  p.elements.push_back(Element::circle(V2(14, 10), 0.4, l));
  p.elements.push_back(Element::circle(V2(5, 11), 0.25, l));
  WorldConfig cfg;
  cfg.ceiling_height_m = 2.8;
  cfg.grid_cell_m = 0.37;
  World w(p, cfg);
  Rng rng(42);
  int walls = 0;
  for (int i = 0; i < 20000; ++i) {
    const V3 o(rng.uniform(0.5, 19.5), rng.uniform(0.5, 14.5), rng.uniform(0.2, 2.6));
    const double az = rng.uniform(0, 2 * M_PI), el = rng.uniform(-0.35, 0.35);
    const V3 d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    // Skip origins inside a pillar.
    if ((o.head<2>() - V2(14, 10)).norm() < 0.45 || (o.head<2>() - V2(5, 11)).norm() < 0.3) continue;
    int elem;
    const double tr = reference_t(p, 2.8, o, d, &elem);
    const Hit h = w.cast(o, d, 1000);
    ASSERT_NEAR(h.t, tr, 1e-7) << "ray " << i;
    if (elem >= 0) {
      ++walls;
      EXPECT_EQ(h.element, elem);
    }
  }
  EXPECT_GT(walls, 1000);
}

TEST(World, WindowsPatchesAndClutter) {
  FloorPlan p = box_room(10, 8);
  const int win = p.layer_index("windows");
  p.elements[0].layer = win;  // the south wall y = 0 is a window
  WorldConfig cfg;
  cfg.ceiling_height_m = 3.0;
  cfg.window_sill_m = 0.9;
  cfg.window_head_m = 2.2;
  World w(p, cfg);
  // Through the glass at 1.5 m: passes (nothing outside at this height -> no return).
  EXPECT_EQ(w.cast(V3(5, 4, 1.5), V3(0, -1, 0), 100).label, Label::kNone);
  // Below the sill: wall.
  Hit h = w.cast(V3(5, 4, 0.5), V3(0, -1, 0), 100);
  EXPECT_EQ(h.label, Label::kWall);
  EXPECT_NEAR(h.t, 4.0, 1e-9);
  // Above the head: wall.
  EXPECT_EQ(w.cast(V3(5, 4, 2.5), V3(0, -1, 0), 100).label, Label::kWall);

  // Missing ceiling patch: a vertical ray gets no return; a sloped patch gives its height.
  CeilingPatch open;
  open.box = Box2{V2(1, 1), V2(3, 3)};
  open.open = true;
  w.add_ceiling_patch(open);
  EXPECT_EQ(w.cast(V3(2, 2, 1), V3(0, 0, 1), 100).label, Label::kNone);
  CeilingPatch slope;
  slope.box = Box2{V2(6, 1), V2(10, 8)};
  slope.h0 = 3.0;
  slope.slope = V2(0.1, 0);
  w.add_ceiling_patch(slope);
  h = w.cast(V3(8, 4, 1), V3(0, 0, 1), 100);
  EXPECT_EQ(h.label, Label::kCeiling);
  EXPECT_NEAR(h.t, 3.0 + 0.1 * 2 - 1, 1e-9);

  // Furniture and a person (clutter, not in the plan).
  Furniture f;
  f.center = V2(5, 6);
  f.half = V2(0.5, 0.3);
  f.yaw = M_PI / 2;  // long side along y
  f.z1 = 0.8;
  w.add_furniture(f);
  h = w.cast(V3(5, 4, 0.5), V3(0, 1, 0), 100);
  EXPECT_EQ(h.label, Label::kClutter);
  EXPECT_NEAR(h.t, 6 - 0.5 - 4, 1e-9);
  EXPECT_EQ(w.cast(V3(5, 4, 1.0), V3(0, 1, 0), 100).label, Label::kWall);  // above the table
  Person pers;
  pers.path = {V2(8, 2), V2(8, 6)};
  pers.speed = 1.0;
  pers.radius = 0.2;
  w.add_person(pers);
  w.set_time(1.0);  // at (8, 3)
  h = w.cast(V3(5, 3, 1.0), V3(1, 0, 0), 100);
  EXPECT_EQ(h.label, Label::kClutter);
  EXPECT_NEAR(h.t, 2.8, 1e-9);
  w.set_time(3.0);  // at (8, 5)
  EXPECT_EQ(w.cast(V3(5, 3, 1.0), V3(1, 0, 0), 100).label, Label::kWall);
}
