#include "fploc/sim/ceiling_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "fploc/core/rng.h"
#include "fploc/sim/world.h"

namespace fploc::sim {
namespace {

bool inside(const Box2& b, const Eigen::Vector2d& p) {
  return p.x() >= b.min.x() && p.x() <= b.max.x() && p.y() >= b.min.y() && p.y() <= b.max.y();
}

// A rectangle of the bounds given in fractions of its size.
Box2 frac(const Box2& b, double x0, double y0, double x1, double y1) {
  Box2 r;
  r.min = b.min + Eigen::Vector2d(x0 * b.size().x(), y0 * b.size().y());
  r.max = b.min + Eigen::Vector2d(x1 * b.size().x(), y1 * b.size().y());
  return r;
}

constexpr double kLampDrop = 0.45, kLampThick = 0.08, kLampHalf = 0.3, kLampPitch = 3.0;
constexpr double kBeamDepth = 0.3, kBeamHalfWidth = 0.125, kBeamPitch = 4.0, kBeamMaxLen = 8.0;
constexpr double kDuctDrop = 0.55, kDuctDepth = 0.4, kDuctHalfWidth = 0.25;
constexpr double kGridPitch = 1.2, kGridHalfWidth = 0.0125, kGridDepth = 0.04, kGridSpan = 7.2;

void add_areas(CeilingMap& m, const Box2& b, Rng& rng) {
  const double h = m.default_height_m;
  const double j1 = rng.uniform(-0.05, 0.05), j2 = rng.uniform(-0.05, 0.05);
  const bool swap = rng.uniform() < 0.5;
  CeilingArea drop{"drop ceiling", frac(b, 0.0, 0.0, 0.45 + j1, 0.40 + j2), h - 0.35};
  CeilingArea hall{"high hall", frac(b, 0.55 + j1, 0.0, 1.0, 0.40 + j2), h + 0.8};
  if (swap) {
    drop.box = frac(b, 0.55 + j1, 0.0, 1.0, 0.40 + j2);
    hall.box = frac(b, 0.0, 0.0, 0.45 + j1, 0.40 + j2);
  }
  CeilingArea corridor{"low corridor", frac(b, 0.0, 0.45 + j2, 1.0, 0.55 + j2), h - 0.5};
  CeilingArea roof{"sloped roof", frac(b, 0.6 + j1, 0.62 + j2, 1.0, 1.0), h};
  roof.slope = Eigen::Vector2d(0.12, 0.0);
  m.areas.insert(m.areas.end(), {drop, hall, corridor, roof});
}

void add_atrium(CeilingMap& m, const Box2& b) {
  // Double height over the centre (if an area is there already, the atrium replaces it).
  CeilingArea atrium{"atrium", frac(b, 0.35, 0.3, 0.65, 0.7), 2.0 * m.default_height_m};
  std::vector<CeilingArea> keep;
  for (const auto& a : m.areas) {
    const bool overlap = a.box.min.x() < atrium.box.max.x() && a.box.max.x() > atrium.box.min.x() &&
                         a.box.min.y() < atrium.box.max.y() && a.box.max.y() > atrium.box.min.y();
    if (!overlap) keep.push_back(a);
  }
  keep.push_back(atrium);
  m.areas = keep;
}

void add_object(CeilingMap& m, const std::string& kind, const Eigen::Vector2d& c, double yaw,
                const Eigen::Vector2d& half, double below_top, double depth) {
  const double h = m.height_at(c);
  if (!std::isfinite(h)) return;
  CeilingObject o;
  o.kind = kind;
  o.center = c;
  o.yaw = yaw;
  o.half = half;
  o.z1 = h - below_top;
  o.z0 = o.z1 - depth;
  m.objects.push_back(o);
}

void add_clutter(CeilingMap& m, const Box2& b, Rng& rng) {
  const Eigen::Vector2d sz = b.size();
  // Lamps on a grid (offset by seed), hanging kLampDrop below the local ceiling.
  const Eigen::Vector2d off(rng.uniform(0.5, kLampPitch - 0.5), rng.uniform(0.5, kLampPitch - 0.5));
  for (double x = b.min.x() + off.x(); x < b.max.x() - 0.5; x += kLampPitch)
    for (double y = b.min.y() + off.y(); y < b.max.y() - 0.5; y += kLampPitch)
      add_object(m, "lamp", {x, y}, 0.0, {kLampHalf, kLampHalf}, kLampDrop - kLampThick, kLampThick);
  // Beams across y (pieces of at most kBeamMaxLen, each under its own ceiling).
  const double bx = rng.uniform(1.0, kBeamPitch);
  for (double x = b.min.x() + bx; x < b.max.x() - 0.5; x += kBeamPitch)
    for (double y0 = b.min.y(); y0 < b.max.y(); y0 += kBeamMaxLen) {
      const double y1 = std::min(b.max.y(), y0 + kBeamMaxLen);
      add_object(m, "beam", {x, 0.5 * (y0 + y1)}, 0.0, {kBeamHalfWidth, 0.5 * (y1 - y0)}, 0.0, kBeamDepth);
    }
  // One duct along x at a quarter of the depth.
  const double yd = b.min.y() + 0.25 * sz.y();
  for (double x0 = b.min.x(); x0 < b.max.x(); x0 += kBeamMaxLen) {
    const double x1 = std::min(b.max.x(), x0 + kBeamMaxLen);
    add_object(m, "duct", {0.5 * (x0 + x1), yd}, 0.0, {0.5 * (x1 - x0), kDuctHalfWidth}, kDuctDrop - kDuctDepth, kDuctDepth);
  }
  // A drop-ceiling grid (T-bars) over one square near the start corner of the bounds.
  const Eigen::Vector2d g0 = b.min + Eigen::Vector2d(0.1 * sz.x(), 0.6 * sz.y());
  const double span = std::min({kGridSpan, 0.4 * sz.x(), 0.35 * sz.y()});
  for (double t = 0; t <= span + 1e-9; t += kGridPitch) {
    add_object(m, "grid", g0 + Eigen::Vector2d(t, 0.5 * span), 0.0, {kGridHalfWidth, 0.5 * span}, 0.0, kGridDepth);
    add_object(m, "grid", g0 + Eigen::Vector2d(0.5 * span, t), 0.0, {0.5 * span, kGridHalfWidth}, 0.0, kGridDepth);
  }
}

}  // namespace

double CeilingMap::height_at(const Eigen::Vector2d& p) const {
  for (const auto& a : areas)
    if (inside(a.box, p)) return a.open ? std::numeric_limits<double>::quiet_NaN() : a.height_at(p);
  return default_height_m;
}

std::vector<std::string> ceiling_map_kinds() { return {"areas", "atrium", "clutter", "mixed"}; }

CeilingMap make_ceiling_map(const std::string& kind, const Box2& bounds, double default_height_m, uint64_t seed) {
  CeilingMap m;
  m.default_height_m = default_height_m;
  Rng rng(mix_seed(seed, 0xCE11u));
  if (kind == "areas") {
    add_areas(m, bounds, rng);
  } else if (kind == "atrium") {
    add_atrium(m, bounds);
  } else if (kind == "clutter") {
    add_clutter(m, bounds, rng);
  } else if (kind == "mixed") {
    add_areas(m, bounds, rng);
    for (auto& a : m.areas)  // the high hall becomes a double-height atrium
      if (a.name == "high hall") {
        a.name = "atrium";
        a.height_m = 2.0 * default_height_m;
      }
    add_clutter(m, bounds, rng);
  } else {
    std::string valid;
    for (const auto& k : ceiling_map_kinds()) valid += " " + k;
    throw std::invalid_argument("unknown ceiling kind '" + kind + "' (valid:" + valid + ")");
  }
  return m;
}

namespace {
// A protobuf text-format string literal.
std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}
}  // namespace

std::string ceiling_map_building_text(const CeilingMap& m, const std::string& plan_file, const std::string& floor,
                                      const std::vector<std::string>& layers, const std::string& units) {
  std::ostringstream o;
  o.precision(10);
  o << "# The simulated floor's ceilings (fploc::sim::ceiling_map_building_text).\n";
  o << "name: \"simulated\"\nfloor {\n  name: " << quoted(floor) << "\n  plan { file: " << quoted(plan_file);
  for (const auto& l : layers) o << " layers: " << quoted(l);
  if (!units.empty()) o << " units: " << quoted(units);
  o << " }\n  elevation_m: 0\n  ceiling_height_m: " << m.default_height_m << "\n";
  for (const auto& a : m.areas) {
    if (a.open) continue;
    o << "  area {\n    name: " << quoted(a.name) << "\n";
    if (a.slope.squaredNorm() > 0)
      o << "    sloped_ceiling { height_m: " << a.height_m << " x: " << a.box.min.x() << " y: " << a.box.min.y()
        << " slope_x: " << a.slope.x() << " slope_y: " << a.slope.y() << " }\n";
    else
      o << "    ceiling_height_m: " << a.height_m << "\n";
    o << "    polygon { x: " << a.box.min.x() << " y: " << a.box.min.y() << " } polygon { x: " << a.box.max.x()
      << " y: " << a.box.min.y() << " } polygon { x: " << a.box.max.x() << " y: " << a.box.max.y()
      << " } polygon { x: " << a.box.min.x() << " y: " << a.box.max.y() << " }\n  }\n";
  }
  o << "}\n";
  return o.str();
}

void apply_ceiling_map(const CeilingMap& m, World& world) {
  for (const auto& a : m.areas) {
    CeilingPatch p;
    p.box = a.box;
    p.open = a.open;
    p.h0 = a.height_m;
    p.slope = a.slope;
    world.add_ceiling_patch(p);
  }
  for (const auto& o : m.objects) {
    Furniture f;
    f.center = o.center;
    f.yaw = o.yaw;
    f.half = o.half;
    f.z0 = o.z0;
    f.z1 = o.z1;
    f.reflectivity = o.kind == "lamp" ? 90 : 40;
    world.add_furniture(f);
  }
}

}  // namespace fploc::sim
