#include "fploc/floorplan/incline.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fploc {

double Incline::tau(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = head - foot;
  const double l2 = d.squaredNorm();
  return l2 > 0 ? (p - foot).dot(d) / l2 : 0.0;
}

bool Incline::contains(const Eigen::Vector2d& p) const {
  FloorConnection c;
  c.polygon = polygon;
  return c.contains(p);
}

std::vector<Incline> building_inclines(const Building& b) {
  std::vector<Incline> out;
  for (const auto& c : b.connections) {
    if (c.kind != ConnectionKind::kRamp && c.kind != ConnectionKind::kStairs) continue;
    const std::string where = b.source + ": connection '" + c.name + "' (" + to_string(c.kind) + ")";
    if (c.polygon.size() != 4)
      throw std::runtime_error(where + ": a ramp or stairs polygon needs 4 vertices (foot edge v0-v1, head edge v2-v3), got " +
                               std::to_string(c.polygon.size()));
    Incline in;
    in.name = c.name;
    in.kind = c.kind;
    in.from_floor = b.floor_index(c.from_floor);
    in.to_floor = b.floor_index(c.to_floor);
    if (in.from_floor < 0 || in.to_floor < 0) throw std::runtime_error(where + ": unknown floor");
    in.polygon = c.polygon;
    in.foot = 0.5 * (c.polygon[0] + c.polygon[1]);
    in.head = 0.5 * (c.polygon[2] + c.polygon[3]);
    in.z_foot = b.floors[size_t(in.from_floor)].elevation;
    in.z_head = b.floors[size_t(in.to_floor)].elevation;
    if (std::abs(in.z_head - in.z_foot) < 1e-6)
      throw std::runtime_error(where + ": floors '" + c.from_floor + "' and '" + c.to_floor + "' have the same elevation");
    if ((in.head - in.foot).norm() < 0.5) throw std::runtime_error(where + ": foot and head edges are less than 0.5 m apart");
    out.push_back(std::move(in));
  }
  return out;
}

}  // namespace fploc
