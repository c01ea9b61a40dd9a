#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fploc/floorplan/plan_position.h"

using namespace fploc;

namespace {
// An L-shaped building: the 10 x 4 m wing along x and the 4 x 10 m wing along y, a 1 m doorway in the
// outer wall at (5, 0), and a round pillar in the corner room.
FloorPlan l_building() {
  FloorPlan p;
  auto s = [&](double x1, double y1, double x2, double y2) { p.elements.push_back(Element::segment({x1, y1}, {x2, y2})); };
  s(0, 0, 4.5, 0);
  s(5.5, 0, 10, 0);  // doorway 4.5 .. 5.5
  s(10, 0, 10, 4);
  s(10, 4, 4, 4);
  s(4, 4, 4, 10);
  s(4, 10, 0, 10);
  s(0, 10, 0, 0);
  p.elements.push_back(Element::circle({2, 2}, 0.3));
  return p;
}
}  // namespace

TEST(PlanPosition, InsideTheWallsIsEnclosed) {
  const FloorPlan p = l_building();
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(2, 8), Eigen::Vector2d(8, 2), Eigen::Vector2d(5, 0.5)}) {
    const PlanPosition w = locate_in_plan(p, q);
    EXPECT_TRUE(w.inside_extent());
    EXPECT_TRUE(w.enclosed()) << q.transpose() << ": " << w.hits << " of " << w.directions;
  }
  // Beside the pillar the rays towards it meet the circle: all 16 meet something.
  EXPECT_EQ(locate_in_plan(p, {1, 1}).hits, 16);
}

TEST(PlanPosition, InTheBoxBesideTheBuildingIsNotEnclosed) {
  // (8, 8) lies in the 10 x 10 m bounding box but outside the L: the building spans less than 180 degrees.
  const PlanPosition w = locate_in_plan(l_building(), {8, 8});
  EXPECT_TRUE(w.inside_extent());
  EXPECT_FALSE(w.enclosed()) << w.hits << " of " << w.directions;
  EXPECT_LE(2 * w.hits, w.directions);
}

TEST(PlanPosition, OutsideTheExtentIsMeasured) {
  const FloorPlan p = l_building();
  EXPECT_NEAR(locate_in_plan(p, {13, 14}).outside_m, 5.0, 1e-12);  // 3 m right, 4 m above the box
  EXPECT_NEAR(locate_in_plan(p, {-0.5, 5}).outside_m, 0.5, 1e-12);
  EXPECT_FALSE(locate_in_plan(p, {-0.5, 5}).enclosed());
  // Absurd coordinates: no overflow to inf or NaN on the way (hypot).
  EXPECT_GT(locate_in_plan(p, {1e308, 1}).outside_m, 1e307);
  EXPECT_GT(locate_in_plan(p, {-1e200, 1e200}).outside_m, 1e200);
  EXPECT_EQ(locate_in_plan(p, {std::nan(""), 1}).outside_m, std::numeric_limits<double>::infinity());
  EXPECT_EQ(locate_in_plan(FloorPlan{}, {0, 0}).outside_m, std::numeric_limits<double>::infinity());
}

TEST(PlanPosition, ArcsCountOnlyWhereDrawn) {
  FloorPlan p;
  p.elements.push_back(Element::arc({0, 0}, 2, 0, M_PI));  // the upper half circle
  p.elements.push_back(Element::segment({-3, -3}, {3, -3}));  // something below, so the box holds the centre
  const PlanPosition w = locate_in_plan(p, {0, 0}, 4);     // rays +x, +y, -x, -y
  // +x and -x graze the arc's ends (angle 0 and pi), +y meets it, -y meets the segment.
  EXPECT_EQ(w.hits, 4);
  const PlanPosition v = locate_in_plan(p, {0, -1}, 4);
  // From (0, -1): +y meets the arc at (0, 2); -y the segment; +x meets the circle at angle < 0 (not drawn).
  EXPECT_EQ(v.hits, 2);
}
