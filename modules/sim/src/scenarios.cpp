#include "fploc/sim/scenarios.h"

#include <cmath>

#include "fploc/sim/demo_building.h"

namespace fploc::sim {
namespace {

using V = Eigen::Vector2d;

void seg(FloorPlan& p, int layer, V a, V b) { p.elements.push_back(Element::segment(a, b, layer)); }

// Intersection of lines p + t d and q + s e.
V intersect(const V& p, const V& d, const V& q, const V& e) {
  const double den = d.x() * e.y() - d.y() * e.x();
  const V w = q - p;
  const double t = (w.x() * e.y() - w.y() * e.x()) / den;
  return p + t * d;
}

// Corridor centre line (counter-clockwise) and the half width of each edge.
void corridor_centre(std::vector<V>& pts, std::vector<double>& half) {
  const double a = 10.25, b = 1.5;
  pts = {V(-a, -a), V(0, -a - b), V(a, -a), V(a + b, 0), V(a, a), V(0, a + b), V(-a, a), V(-a - b, 0)};
  half = {1.5, 0.8, 1.5, 0.8, 1.5, 0.8, 1.5, 0.8};
}

// Offsets the closed polygon by +-half per edge (sign +1 = outward for a CCW polygon).
std::vector<V> offset_polygon(const std::vector<V>& pts, const std::vector<double>& half, double sign) {
  const size_t n = pts.size();
  std::vector<V> out(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t ip = (i + n - 1) % n;  // edge ip: pts[ip] -> pts[i]; edge i: pts[i] -> pts[i+1]
    const V d0 = (pts[i] - pts[ip]).normalized(), d1 = (pts[(i + 1) % n] - pts[i]).normalized();
    const V n0(d0.y(), -d0.x()), n1(d1.y(), -d1.x());
    out[i] = intersect(pts[ip] + sign * half[ip] * n0, d0, pts[i] + sign * half[i] * n1, d1);
  }
  return out;
}

std::vector<V> densify_closed(const std::vector<V>& pts, double step) {
  std::vector<V> out;
  for (size_t i = 0; i < pts.size(); ++i) {
    const V a = pts[i], b = pts[(i + 1) % pts.size()];
    const int k = std::max(1, int(std::ceil((b - a).norm() / step)));
    for (int j = 0; j < k; ++j) out.push_back(a + (b - a) * (double(j) / k));
  }
  return out;
}

struct SpeedRow {
  const char* base;
  const char* speed;
  double v_max, v_avg, length;
};
// The paper's Tables I and II (max speed, average speed, length).
constexpr SpeedRow kPaper[] = {
    {"room-small-loop", "fast", 0.8719, 0.6236, 25.797},   {"room-small-loop", "medium", 0.5641, 0.4090, 25.849},
    {"room-small-loop", "slow", 0.4425, 0.3109, 25.714},   {"room-large-loop", "fast", 0.9213, 0.7253, 46.725},
    {"room-large-loop", "medium", 0.6878, 0.5357, 46.773}, {"room-large-loop", "slow", 0.4742, 0.3552, 46.421},
    {"room-no-loop", "fast", 0.8458, 0.6926, 25.287},      {"room-no-loop", "medium", 0.5277, 0.3904, 25.322},
    {"room-no-loop", "slow", 0.4028, 0.2954, 25.208},      {"corridor-loop", "fast", 1.2678, 1.0487, 81.448},
    {"corridor-loop", "medium", 0.9296, 0.7777, 81.789},   {"corridor-loop", "slow", 0.6603, 0.5547, 82.072},
};
// Every other family runs at DESIGN.md's room speeds; its length follows from the plan or the journey.
constexpr SpeedRow kRoomSpeeds[] = {
    {"", "fast", 0.90, 0.65, 0}, {"", "medium", 0.55, 0.40, 0}, {"", "slow", 0.45, 0.30, 0}};
constexpr const char* kFamilies[] = {
    "auto-loop",  // any plan: a loop around its free space
    // auto-loop with the ceilings of a real building (ceiling_map.h kinds).
    "building-areas", "building-atrium", "building-clutter", "building-mixed",
    // Journeys through the demo building (ramp, lift, thresholds): demo_building.h.
    "building-twofloor", "building-ramp", "building-thresholds"};

std::vector<SpeedRow> all_rows() {
  std::vector<SpeedRow> rows(std::begin(kPaper), std::end(kPaper));
  for (const char* family : kFamilies)
    for (SpeedRow r : kRoomSpeeds) {
      r.base = family;
      rows.push_back(r);
    }
  return rows;
}

}  // namespace

FloorPlan demo_room_plan() {
  FloorPlan p;
  p.source = "demo room (fploc::sim::demo_room_plan)";
  const int walls = p.layer_index("walls"), windows = p.layer_index("windows"), cols = p.layer_index("columns");
  const double W = 16.0, H = 12.5, t = 0.25;
  const double d0 = 5.75, d1 = 6.75;  // door gaps (y) on the west and east walls
  for (double off : {0.0, t}) {
    const double x0 = 0.0 - off, x1 = W + off, y0 = 0.0 - off, y1 = H + off;
    // South and north walls with two windows each (x in [3,6] and [10,13]).
    for (double y : {y0, y1}) {
      seg(p, walls, V(x0, y), V(3, y));
      seg(p, windows, V(3, y), V(6, y));
      seg(p, walls, V(6, y), V(10, y));
      seg(p, windows, V(10, y), V(13, y));
      seg(p, walls, V(13, y), V(x1, y));
    }
    // West and east walls with a door each.
    for (double x : {x0, x1}) {
      seg(p, walls, V(x, y0), V(x, d0));
      seg(p, walls, V(x, d1), V(x, y1));
    }
  }
  // Door jambs.
  for (double y : {d0, d1}) {
    seg(p, walls, V(0, y), V(-t, y));
    seg(p, walls, V(W, y), V(W + t, y));
  }
  // Corridors outside the doors (2 m wide).
  seg(p, walls, V(-t - 2.0, 2.5), V(-t - 2.0, 10.0));
  seg(p, walls, V(W + t + 2.0, 2.5), V(W + t + 2.0, 10.0));
  // Pillars: square 0.6 x 0.6 at (4.5, 4.0) and (11.5, 8.5); round r = 0.3 at (11.5, 4.0) and (4.5, 8.5).
  for (V c : {V(4.5, 4.0), V(11.5, 8.5)}) {
    const double h = 0.3;
    const V q[4] = {c + V(-h, -h), c + V(h, -h), c + V(h, h), c + V(-h, h)};
    for (int i = 0; i < 4; ++i) seg(p, cols, q[i], q[(i + 1) % 4]);
  }
  p.elements.push_back(Element::circle(V(11.5, 4.0), 0.3, cols));
  p.elements.push_back(Element::circle(V(4.5, 8.5), 0.3, cols));
  return p;
}

FloorPlan demo_corridor_plan() {
  FloorPlan p;
  p.source = "demo corridor (fploc::sim::demo_corridor_plan)";
  const int walls = p.layer_index("walls");
  std::vector<V> c;
  std::vector<double> half;
  corridor_centre(c, half);
  for (double sign : {1.0, -1.0}) {
    const auto poly = offset_polygon(c, half, sign);
    for (size_t i = 0; i < poly.size(); ++i) seg(p, walls, poly[i], poly[(i + 1) % poly.size()]);
  }
  return p;
}

std::vector<std::string> scenario_names() {
  std::vector<std::string> out;
  for (const auto& r : all_rows()) out.push_back(std::string(r.base) + "-" + r.speed);
  return out;
}

bool scenario_spec(const std::string& name, ScenarioSpec& out, std::string* error) {
  for (const auto& r : all_rows()) {
    if (name != std::string(r.base) + "-" + r.speed) continue;
    ScenarioSpec s;
    s.name = name;
    s.base = r.base;
    s.speed_name = r.speed;
    s.speed = {r.v_max, r.v_avg};
    s.length = r.length;
    if (s.base == "room-small-loop") {
      s.plan_kind = "room";
      s.control = {V(6, 2.6), V(7, 2.1), V(9, 2.1), V(10, 2.6), V(10, 9.9), V(9, 10.4), V(7, 10.4), V(6, 9.9)};
    } else if (s.base == "room-large-loop") {
      s.plan_kind = "room";
      s.control = {V(1.6, 2.6), V(2.6, 1.6), V(13.4, 1.6), V(14.4, 2.6), V(14.4, 9.9), V(13.4, 10.9), V(2.6, 10.9), V(1.6, 9.9)};
    } else if (s.base == "room-no-loop") {
      s.plan_kind = "room";
      s.closed = false;
      s.control = {V(1.5, 6.25), V(3.0, 6.25), V(6.6, 2.0), V(8.0, 6.25), V(9.4, 10.5), V(13.0, 6.25), V(14.5, 6.25)};
    } else if (s.base == "corridor-loop") {
      s.plan_kind = "corridor";
      std::vector<V> cl;
      std::vector<double> half;
      corridor_centre(cl, half);
      s.control = densify_closed(cl, 1.0);
    } else if (!demo_building_journey(s.base).empty()) {
      s.plan_kind = "building";
      s.legs = demo_building_journey(s.base);
      s.closed = false;
    } else {
      s.plan_kind = "any";
      if (s.base.rfind("building-", 0) == 0) s.ceilings = s.base.substr(9);
    }
    s.ceiling_m = s.plan_kind == "corridor" ? kCorridorCeilingM : s.plan_kind == "room" ? kRoomCeilingM : 3.0;
    out = std::move(s);
    return true;
  }
  if (error) {
    *error = "unknown scenario '" + name + "' (valid:";
    for (const auto& n : scenario_names()) *error += " " + n;
    *error += ")";
  }
  return false;
}

}  // namespace fploc::sim
