// CeilingMap: the named kinds are deterministic by seed, and the world built from them returns the
// area's ceiling straight up and the hanging objects below it.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "fploc/sim/ceiling_map.h"
#include "fploc/sim/world.h"

using namespace fploc;
using namespace fploc::sim;

namespace {
FloorPlan box_room(double w, double h) {
  FloorPlan p;
  const int l = p.layer_index("walls");
  p.elements.push_back(Element::segment({0, 0}, {w, 0}, l));
  p.elements.push_back(Element::segment({w, 0}, {w, h}, l));
  p.elements.push_back(Element::segment({w, h}, {0, h}, l));
  p.elements.push_back(Element::segment({0, h}, {0, 0}, l));
  return p;
}
double up_hit(const World& w, double x, double y) {
  return w.cast(Eigen::Vector3d(x, y, 1.2), Eigen::Vector3d::UnitZ(), 50.0).t + 1.2;
}
}  // namespace

TEST(CeilingMap, AreasAreWhatTheRaysSee) {
  World world(box_room(20, 16));
  const CeilingMap m = make_ceiling_map("areas", world.bounds(), 3.0, 7);
  ASSERT_EQ(m.areas.size(), 4u);
  apply_ceiling_map(m, world);
  for (const auto& a : m.areas) {
    const Eigen::Vector2d c = 0.5 * (a.box.min + a.box.max);
    EXPECT_NEAR(up_hit(world, c.x(), c.y()), a.height_at(c), 1e-6) << a.name;
    EXPECT_NEAR(m.height_at(c), a.height_at(c), 1e-12) << a.name;
  }
  EXPECT_NEAR(m.height_at(world.bounds().max - Eigen::Vector2d(0.1, 0.1)), m.areas[3].height_at(world.bounds().max - Eigen::Vector2d(0.1, 0.1)), 1e-12);
}

TEST(CeilingMap, DeterministicBySeedAndClutterHangsBelowTheCeiling) {
  World w0(box_room(20, 16));
  const CeilingMap a = make_ceiling_map("mixed", w0.bounds(), 3.0, 1), b = make_ceiling_map("mixed", w0.bounds(), 3.0, 1);
  const CeilingMap c = make_ceiling_map("mixed", w0.bounds(), 3.0, 2);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) EXPECT_EQ(a.objects[i].center, b.objects[i].center);
  bool differs = a.objects.size() != c.objects.size();
  for (size_t i = 0; !differs && i < a.objects.size(); ++i) differs = a.objects[i].center != c.objects[i].center;
  EXPECT_TRUE(differs);
  int lamps = 0;
  for (const auto& o : a.objects) {
    EXPECT_LT(o.z0, o.z1);
    EXPECT_LE(o.z1, a.height_at(o.center) + 1e-9) << o.kind;
    lamps += o.kind == "lamp";
  }
  EXPECT_GT(lamps, 10);
  bool atrium = false;
  for (const auto& ar : a.areas) atrium |= ar.name == "atrium" && std::abs(ar.height_m - 6.0) < 1e-9;
  EXPECT_TRUE(atrium);
  EXPECT_THROW(make_ceiling_map("cathedral", w0.bounds(), 3.0, 1), std::invalid_argument);
}
