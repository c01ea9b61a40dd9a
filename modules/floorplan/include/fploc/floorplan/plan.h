// The floor-plan model: vertical structure elements as 2D primitives (metres, plan frame).
// Line segments (walls), circles (round pillars) and arcs. Element ids are indices into
// FloorPlan::elements and are stable across save/load.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

namespace fploc {

enum class ElementKind : uint8_t { kSegment = 0, kCircle = 1, kArc = 2 };

struct Element {
  ElementKind kind = ElementKind::kSegment;
  // Segment: a -> b. Circle: center c, radius r. Arc: center c, radius r, counter-clockwise from
  // angle a0 to a1 (radians, a1 > a0, a1 - a0 <= 2 pi).
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  double r = 0, a0 = 0, a1 = 0;
  int layer = -1;  // index into FloorPlan::layers (-1 = none)

  static Element segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, int layer = -1);
  static Element circle(const Eigen::Vector2d& c, double r, int layer = -1);
  static Element arc(const Eigen::Vector2d& c, double r, double a0, double a1, int layer = -1);
};

struct ClosestPoint {
  Eigen::Vector2d point;   // closest point on the element
  double distance = 0;     // |p - point|
};

// Exact closest point on an element to p.
ClosestPoint closest_point(const Element& e, const Eigen::Vector2d& p);
inline double distance(const Element& e, const Eigen::Vector2d& p) { return closest_point(e, p).distance; }

// Axis-aligned box.
struct Box2 {
  Eigen::Vector2d min{0, 0}, max{0, 0};
  bool empty() const { return !(max.x() >= min.x() && max.y() >= min.y()); }
  void extend(const Eigen::Vector2d& p);
  void extend(const Box2& b);
  Eigen::Vector2d size() const { return max - min; }
};

// Bounding box of an element (exact for arcs).
Box2 bounds(const Element& e);
// Smallest and largest distance from any point of the box to the element (exact lower bound and a
// valid upper bound: max over the box corners of the distance to the element's nearest point set is
// computed exactly for segments and circles; arcs use a safe bound).
double min_distance(const Element& e, const Box2& box);
double max_distance(const Element& e, const Box2& box);

struct FloorPlan {
  std::vector<Element> elements;
  std::vector<std::string> layers;
  std::string source;        // file it came from
  Box2 bounds() const;
  int layer_index(const std::string& name);  // finds or adds
};

// Brute-force nearest element (the ground truth every faster structure is tested against).
// Returns -1 for an empty plan.
int nearest_element_brute_force(const FloorPlan& plan, const Eigen::Vector2d& p, double* dist = nullptr);

}  // namespace fploc
