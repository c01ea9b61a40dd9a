#include "fploc/sim/building_world.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fploc/core/rng.h"
#include "fploc/sim/perturb.h"

namespace fploc::sim {
namespace {

double cross2(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

}  // namespace

double FloorGround::surface_at(const Eigen::Vector2d& p) const {
  for (const auto& in : inclines)
    if (in.contains(p)) return in.z_at(p) - elevation;
  return 0.0;
}

double FloorGround::wheel_at(const Eigen::Vector2d& p, double r) const {
  double bump = 0;
  for (const auto& t : thresholds) {
    const Eigen::Vector2d d = t.b - t.a;
    const double len = d.norm();
    if (len <= 0) continue;
    const Eigen::Vector2d u = d / len;
    const double along = (p - t.a).dot(u);
    if (along < 0 || along > len) continue;
    const double dx = std::max(0.0, std::abs(cross2(u, p - t.a)) - 0.5 * t.width);
    if (dx >= r) continue;
    bump = std::max(bump, t.height - r + std::sqrt(r * r - dx * dx));
  }
  return surface_at(p) + bump;
}

std::unique_ptr<World> make_floor_world(const Building& b, int floor, const FloorPlan& plan, const FloorWorldOptions& o,
                                        FloorGround* ground, std::string* note) {
  if (floor < 0 || floor >= int(b.floors.size())) throw std::runtime_error(b.source + ": no floor index " + std::to_string(floor));
  const BuildingFloor& f = b.floors[size_t(floor)];
  WorldConfig wc;
  wc.ceiling_height_m = f.ceiling_height > 0 ? f.ceiling_height : 3.0;
  auto w = std::make_unique<World>(plan, wc);
  // Ceilings: the building's areas, first containing a point wins (as BuildingFloor::area_at).
  for (const auto& a : f.areas) {
    CeilingPatch p;
    p.polygon = a.polygon;
    p.box = polygon_bounds(a.polygon);
    p.h0 = a.height_at(p.box.min);
    p.slope = a.slope;
    w->add_ceiling_patch(p);
  }
  FloorGround g;
  g.elevation = f.elevation;
  for (const auto& in : building_inclines(b)) {
    if (in.from_floor != floor && in.to_floor != floor) continue;
    GroundPatch gp;
    gp.name = in.name;
    gp.polygon = in.polygon;
    gp.origin = in.foot;
    gp.h0 = in.z_foot - f.elevation;
    gp.slope = (in.z_head - in.z_foot) / (in.head - in.foot).squaredNorm() * (in.head - in.foot);
    w->add_ground_patch(gp);
    g.inclines.push_back(in);
  }
  if (o.thresholds) {
    Rng rng(mix_seed(o.seed, 0x7E5u, uint64_t(floor)));
    for (const auto& [a, c] : find_doorways(plan)) {
      Threshold t;
      t.a = a;
      t.b = c;
      t.height = rng.uniform(o.threshold_min_m, o.threshold_max_m);
      const Eigen::Vector2d mid = 0.5 * (a + c);
      const double z = g.surface_at(mid);
      Furniture box;
      box.center = mid;
      box.yaw = std::atan2(c.y() - a.y(), c.x() - a.x());
      box.half = Eigen::Vector2d(0.5 * (c - a).norm(), 0.5 * t.width);
      box.z0 = z - 0.01;
      box.z1 = z + t.height;
      box.reflectivity = 22;
      box.ground = true;
      w->add_furniture(box);
      g.thresholds.push_back(t);
    }
  }
  if (note)
    *note = "floor " + f.name + " (elevation " + std::to_string(f.elevation) + " m): " + std::to_string(f.areas.size()) +
            " ceiling areas, " + std::to_string(g.inclines.size()) + " ramps/stairs, " + std::to_string(g.thresholds.size()) +
            " door thresholds";
  if (ground) *ground = std::move(g);
  return w;
}

std::unique_ptr<World> make_lift_car_world(const FloorConnection& lift, double car_height_m) {
  FloorPlan car;
  car.source = "lift car " + lift.name;
  const int layer = car.layer_index("lift");
  for (size_t i = 0; i < lift.polygon.size(); ++i)
    car.elements.push_back(Element::segment(lift.polygon[i], lift.polygon[(i + 1) % lift.polygon.size()], layer));
  WorldConfig wc;
  wc.ceiling_height_m = car_height_m;
  return std::make_unique<World>(car, wc);
}

std::vector<Element> connection_outlines(const Building& b, int floor, bool allow_connections) {
  std::vector<Element> out;
  const std::string name = floor >= 0 && floor < int(b.floors.size()) ? b.floors[size_t(floor)].name : "";
  for (const auto& c : b.connections) {
    if (c.from_floor != name && c.to_floor != name) continue;
    if (c.kind != ConnectionKind::kStairs && allow_connections) continue;
    // The outline, and a fan from the centroid to points every 0.3 m along it (so there is no free
    // space inside for a planner to loop in).
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const auto& v : c.polygon) centre += v;
    centre /= double(c.polygon.size());
    for (size_t i = 0; i < c.polygon.size(); ++i) {
      const Eigen::Vector2d a = c.polygon[i], e = c.polygon[(i + 1) % c.polygon.size()];
      out.push_back(Element::segment(a, e));
      const int n = std::max(1, int(std::ceil((e - a).norm() / 0.3)));
      for (int k = 0; k < n; ++k) out.push_back(Element::segment(centre, a + (e - a) * (double(k) / n)));
    }
  }
  return out;
}

}  // namespace fploc::sim
