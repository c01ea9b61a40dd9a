#include "fploc/sim/world.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

namespace fploc::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-6;

inline double cross2(const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); }

bool inside(const Box2& b, double x, double y) {
  return x >= b.min.x() && x <= b.max.x() && y >= b.min.y() && y <= b.max.y();
}

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

double angle_in(double ang, double a0) {
  double d = std::fmod(ang - a0, 2 * M_PI);
  if (d < 0) d += 2 * M_PI;
  return d;
}

}  // namespace

bool polygon_contains(const std::vector<Eigen::Vector2d>& poly, double x, double y) {
  bool in = false;
  const size_t n = poly.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[j];
    if ((a.y() > y) != (b.y() > y) && x < (b.x() - a.x()) * (y - a.y()) / (b.y() - a.y()) + a.x()) in = !in;
  }
  return in;
}

Box2 polygon_bounds(const std::vector<Eigen::Vector2d>& poly) {
  Box2 b;
  if (poly.empty()) return b;
  b.min = b.max = poly[0];
  for (const auto& p : poly) {
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

bool CeilingPatch::contains(double x, double y) const {
  if (!inside(box, x, y)) return false;
  return polygon.empty() || polygon_contains(polygon, x, y);
}

const char* label_name(Label l) {
  switch (l) {
    case Label::kNone: return "none";
    case Label::kFloor: return "floor";
    case Label::kCeiling: return "ceiling";
    case Label::kWall: return "wall";
    case Label::kPillar: return "pillar";
    case Label::kClutter: return "clutter";
  }
  return "?";
}

Eigen::Vector2d Person::position(double t) const {
  if (path.empty()) return Eigen::Vector2d::Zero();
  if (path.size() == 1) return path[0];
  double len = 0;
  for (size_t i = 1; i < path.size(); ++i) len += (path[i] - path[i - 1]).norm();
  if (len <= 0) return path[0];
  double u = std::fmod(speed * (t + phase_s), 2 * len);
  if (u < 0) u += 2 * len;
  if (u > len) u = 2 * len - u;
  for (size_t i = 1; i < path.size(); ++i) {
    const double l = (path[i] - path[i - 1]).norm();
    if (u <= l || i + 1 == path.size()) return path[i - 1] + (path[i] - path[i - 1]) * (l > 0 ? std::min(u / l, 1.0) : 0.0);
    u -= l;
  }
  return path.back();
}

World::World(const FloorPlan& plan, WorldConfig cfg) : plan_(plan), cfg_(std::move(cfg)) {
  bounds_ = plan_.bounds();
  if (bounds_.empty()) bounds_ = Box2{Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, 1)};
  wall_top_ = cfg_.ceiling_height_m;
  std::vector<std::string> wl;
  for (const auto& w : cfg_.window_layers) wl.push_back(lower(w));
  for (size_t i = 0; i < plan_.elements.size(); ++i) {
    const Element& e = plan_.elements[i];
    Wall w;
    w.kind = e.kind;
    w.a = e.a;
    w.b = e.b;
    w.c = e.c;
    w.r = e.r;
    w.a0 = e.a0;
    w.a1 = e.a1;
    w.element = int32_t(i);
    w.label = e.kind == ElementKind::kCircle ? Label::kPillar : Label::kWall;
    w.reflectivity = e.kind == ElementKind::kCircle ? 45 : 35;
    bool window = false;
    if (e.layer >= 0 && e.layer < int(plan_.layers.size())) {
      const std::string ln = lower(plan_.layers[size_t(e.layer)]);
      for (const auto& p : wl)
        if (!p.empty() && ln.find(p) != std::string::npos) window = true;
    }
    if (e.kind == ElementKind::kSegment && (e.b - e.a).norm() < 1e-9) continue;
    if (window) {
      w.nz = 2;
      w.z[0] = 0.f;
      w.z[1] = float(cfg_.window_sill_m);
      w.z[2] = float(cfg_.window_head_m);
      w.z[3] = 1e6f;  // clipped by wall_top_ below
    } else {
      w.nz = 1;
      w.z[0] = 0.f;
      w.z[1] = 1e6f;
    }
    walls_.push_back(w);
  }
  // Grid.
  cell_ = cfg_.grid_cell_m > 0 ? cfg_.grid_cell_m : 0.5;
  const Eigen::Vector2d ext = bounds_.size();
  // Keep the grid at most ~4M cells for huge plans.
  while ((ext.x() / cell_ + 3) * (ext.y() / cell_ + 3) > 4e6) cell_ *= 2;
  grid_min_ = bounds_.min - Eigen::Vector2d::Constant(cell_);
  nx_ = std::max(1, int(std::ceil(ext.x() / cell_)) + 2);
  ny_ = std::max(1, int(std::ceil(ext.y() / cell_)) + 2);
  std::vector<std::vector<uint32_t>> cells(size_t(nx_) * ny_);
  for (size_t wi = 0; wi < walls_.size(); ++wi) {
    const Element& e = plan_.elements[size_t(walls_[wi].element)];
    const Box2 bb = fploc::bounds(e);
    const int x0 = std::clamp(int(std::floor((bb.min.x() - grid_min_.x()) / cell_)), 0, nx_ - 1);
    const int x1 = std::clamp(int(std::floor((bb.max.x() - grid_min_.x()) / cell_)), 0, nx_ - 1);
    const int y0 = std::clamp(int(std::floor((bb.min.y() - grid_min_.y()) / cell_)), 0, ny_ - 1);
    const int y1 = std::clamp(int(std::floor((bb.max.y() - grid_min_.y()) / cell_)), 0, ny_ - 1);
    for (int iy = y0; iy <= y1; ++iy)
      for (int ix = x0; ix <= x1; ++ix) {
        Box2 cb;
        cb.min = grid_min_ + Eigen::Vector2d(ix * cell_, iy * cell_) - Eigen::Vector2d::Constant(1e-6);
        cb.max = cb.min + Eigen::Vector2d::Constant(cell_ + 2e-6);
        if (fploc::min_distance(e, cb) <= 1e-6) cells[size_t(iy) * nx_ + ix].push_back(uint32_t(wi));
      }
  }
  cell_start_.assign(cells.size() + 1, 0);
  for (size_t i = 0; i < cells.size(); ++i) cell_start_[i + 1] = cell_start_[i] + uint32_t(cells[i].size());
  cell_walls_.reserve(cell_start_.back());
  for (const auto& c : cells) cell_walls_.insert(cell_walls_.end(), c.begin(), c.end());
}

void World::add_ground_patch(GroundPatch p) {
  p.box = polygon_bounds(p.polygon);
  for (const auto& v : p.polygon) {
    const double h = p.height(v.x(), v.y());
    wall_bottom_ = std::min(wall_bottom_, h - 0.5);
    wall_top_ = std::max(wall_top_, h + cfg_.ceiling_height_m);
  }
  ground_.push_back(std::move(p));
  for (auto& w : walls_) w.z[0] = float(wall_bottom_);
}

bool World::in_ground_patch(double x, double y) const {
  for (const auto& g : ground_)
    if (inside(g.box, x, y) && polygon_contains(g.polygon, x, y)) return true;
  return false;
}

double World::ground_at(double x, double y) const {
  for (const auto& g : ground_)
    if (inside(g.box, x, y) && polygon_contains(g.polygon, x, y)) return g.height(x, y);
  return 0;
}

void World::add_ceiling_patch(const CeilingPatch& p0) {
  CeilingPatch p = p0;
  if (!p.polygon.empty()) p.box = polygon_bounds(p.polygon);
  patches_.push_back(p);
  if (!p.open) {
    for (double x : {p.box.min.x(), p.box.max.x()})
      for (double y : {p.box.min.y(), p.box.max.y()}) wall_top_ = std::max(wall_top_, p.height(x, y));
  } else {
    wall_top_ = std::max(wall_top_, cfg_.ceiling_height_m + 1.0);
  }
}

void World::add_furniture(const Furniture& f) {
  furniture_.push_back(f);
  furn_cs_.emplace_back(std::cos(f.yaw), std::sin(f.yaw), f.half.norm());
}

void World::set_time(double t) {
  people_pos_.resize(people_.size());
  for (size_t i = 0; i < people_.size(); ++i) people_pos_[i] = people_[i].position(t);
}

double World::ceiling_at(double x, double y) const {
  if (!inside(bounds_, x, y)) return std::numeric_limits<double>::quiet_NaN();
  for (const auto& p : patches_)
    if (p.contains(x, y)) return p.open ? std::numeric_limits<double>::quiet_NaN() : p.height(x, y);
  return cfg_.ceiling_height_m;
}

double World::ceiling_t(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax) const {
  if (d.z() <= 1e-12) return kInf;
  double best = kInf;
  {
    const double t = (cfg_.ceiling_height_m - o.z()) / d.z();
    if (t > kEps && t < tmax) {
      const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
      if (inside(bounds_, x, y)) {
        bool in_patch = false;
        for (const auto& p : patches_)
          if (p.contains(x, y)) {
            in_patch = true;
            break;
          }
        if (!in_patch) best = t;
      }
    }
  }
  for (size_t pi = 0; pi < patches_.size(); ++pi) {
    const CeilingPatch& p = patches_[pi];
    if (p.open) continue;
    const double den = d.z() - p.slope.x() * d.x() - p.slope.y() * d.y();
    if (std::abs(den) < 1e-12) continue;
    const double t = (p.h0 + p.slope.x() * (o.x() - p.box.min.x()) + p.slope.y() * (o.y() - p.box.min.y()) - o.z()) / den;
    if (t > kEps && t < std::min(tmax, best)) {
      const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
      if (!p.contains(x, y) || !inside(bounds_, x, y)) continue;
      // Overlapping patches: the first one containing the point owns it (as ceiling_at, and as a building's
      // areas: BuildingFloor::area_at), not the lowest plane.
      bool first = true;
      for (size_t k = 0; k < pi && first; ++k) first = !patches_[k].contains(x, y);
      if (first) best = t;
    }
  }
  return best;
}

bool World::hit_wall(const Wall& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax, Hit& h) const {
  const Eigen::Vector2d o2 = o.head<2>(), d2 = d.head<2>();
  auto z_ok = [&](double t) {
    const double z = o.z() + t * d.z();
    const double top = wall_top_;
    if (z >= w.z[0] && z <= std::min<double>(w.z[1], top)) return true;
    if (w.nz == 2 && z >= w.z[2] && z <= std::min<double>(w.z[3], top)) return true;
    return false;
  };
  if (w.kind == ElementKind::kSegment) {
    const Eigen::Vector2d e = w.b - w.a;
    const double den = cross2(d2, e);
    if (std::abs(den) < 1e-15) return false;
    const Eigen::Vector2d ao = w.a - o2;
    const double t = cross2(ao, e) / den;
    if (t <= kEps || t >= tmax) return false;
    const double s = cross2(ao, d2) / den;
    if (s < 0 || s > 1) return false;
    if (!z_ok(t)) return false;
    Eigen::Vector2d n(-e.y(), e.x());
    n.normalize();
    if (n.dot(d2) > 0) n = -n;
    h.t = t;
    h.normal = Eigen::Vector3d(n.x(), n.y(), 0);
  } else {
    const Eigen::Vector2d f = o2 - w.c;
    const double A = d2.squaredNorm();
    if (A < 1e-18) return false;
    const double B = f.dot(d2), C = f.squaredNorm() - w.r * w.r;
    const double disc = B * B - A * C;
    if (disc < 0) return false;
    const double sq = std::sqrt(disc);
    const double roots[2] = {(-B - sq) / A, (-B + sq) / A};
    bool found = false;
    for (double t : roots) {
      if (t <= kEps || t >= tmax) continue;
      if (w.kind == ElementKind::kArc) {
        const Eigen::Vector2d p = o2 + t * d2 - w.c;
        if (angle_in(std::atan2(p.y(), p.x()), w.a0) > w.a1 - w.a0 + 1e-12) continue;
      }
      if (!z_ok(t)) continue;
      Eigen::Vector2d n = (o2 + t * d2 - w.c).normalized();
      if (n.dot(d2) > 0) n = -n;
      h.t = t;
      h.normal = Eigen::Vector3d(n.x(), n.y(), 0);
      found = true;
      break;
    }
    if (!found) return false;
  }
  h.label = w.label;
  h.element = w.element;
  h.reflectivity = w.reflectivity;
  return true;
}

Hit World::cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max) const {
  Hit best;
  best.t = kInf;
  double tlim = t_max;
  // Floor (everywhere) and ceiling (inside the building).
  // The floor plane z = 0 from above, or from below when the sensor is lower (on a ramp to this floor).
  if (d.z() < -1e-12 || (d.z() > 1e-12 && o.z() < 0 && !ground_.empty())) {
    const double t = -o.z() / d.z();
    if (t > kEps && t < tlim && (ground_.empty() || !in_ground_patch(o.x() + t * d.x(), o.y() + t * d.y()))) {
      best.t = t;
      best.label = Label::kFloor;
      best.normal = Eigen::Vector3d::UnitZ();
      best.reflectivity = 18;
      best.element = -1;
      tlim = t;
    }
  }
  // Ramps, stairs, the storey below: sloped or lower/higher floor planes inside their polygons.
  for (size_t gi = 0; gi < ground_.size(); ++gi) {
    const GroundPatch& g = ground_[gi];
    const double den = d.z() - g.slope.x() * d.x() - g.slope.y() * d.y();
    if (std::abs(den) < 1e-12) continue;
    const double t = (g.height(o.x(), o.y()) - o.z()) / den;
    if (!(t > kEps && t < tlim)) continue;
    const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
    if (!inside(g.box, x, y) || !polygon_contains(g.polygon, x, y)) continue;
    bool first = true;  // the first patch containing the point owns it
    for (size_t k = 0; k < gi && first; ++k)
      if (inside(ground_[k].box, x, y) && polygon_contains(ground_[k].polygon, x, y)) first = false;
    if (!first) continue;
    Eigen::Vector3d n(-g.slope.x(), -g.slope.y(), 1.0);
    n.normalize();
    if (n.dot(d) > 0) n = -n;
    best.t = t;
    best.label = Label::kFloor;
    best.normal = n;
    best.reflectivity = 18;
    best.element = -1;
    tlim = t;
  }
  if (d.z() > 1e-12) {
    const double t = ceiling_t(o, d, tlim);
    if (t < tlim) {
      best.t = t;
      best.label = Label::kCeiling;
      best.normal = -Eigen::Vector3d::UnitZ();
      best.reflectivity = 60;
      best.element = -1;
      tlim = t;
    }
  }
  // Clutter: furniture boxes.
  const Eigen::Vector2d o2 = o.head<2>(), d2 = d.head<2>();
  for (size_t i = 0; i < furniture_.size(); ++i) {
    const Furniture& f = furniture_[i];
    const double c = furn_cs_[i].x(), s = furn_cs_[i].y();
    const Eigen::Vector2d rel = o2 - f.center;
    // Bounding-circle rejection in 2D.
    {
      const double a2 = d2.squaredNorm();
      if (a2 > 1e-18) {
        const double tc = std::max(0.0, -rel.dot(d2) / a2);
        if ((rel + tc * d2).squaredNorm() > furn_cs_[i].z() * furn_cs_[i].z()) continue;
      }
    }
    const double lo[3] = {c * rel.x() + s * rel.y(), -s * rel.x() + c * rel.y(), o.z()};
    const double ld[3] = {c * d2.x() + s * d2.y(), -s * d2.x() + c * d2.y(), d.z()};
    const double bmin[3] = {-f.half.x(), -f.half.y(), f.z0}, bmax[3] = {f.half.x(), f.half.y(), f.z1};
    double t0 = kEps, t1 = tlim;
    int axis = -1;
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) {
      if (std::abs(ld[k]) < 1e-15) {
        if (lo[k] < bmin[k] || lo[k] > bmax[k]) ok = false;
        continue;
      }
      double ta = (bmin[k] - lo[k]) / ld[k], tb = (bmax[k] - lo[k]) / ld[k];
      if (ta > tb) std::swap(ta, tb);
      if (ta > t0) {
        t0 = ta;
        axis = k;
      }
      t1 = std::min(t1, tb);
      if (t0 > t1) ok = false;
    }
    if (!ok || axis < 0 || t0 >= tlim) continue;  // axis < 0: ray starts inside the box
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    if (axis == 2) {
      n.z() = d.z() > 0 ? -1 : 1;
    } else {
      Eigen::Vector2d nl = axis == 0 ? Eigen::Vector2d(ld[0] > 0 ? -1 : 1, 0) : Eigen::Vector2d(0, ld[1] > 0 ? -1 : 1);
      n.head<2>() = Eigen::Vector2d(c * nl.x() - s * nl.y(), s * nl.x() + c * nl.y());
    }
    best.t = t0;
    best.label = f.ground ? Label::kFloor : Label::kClutter;
    best.element = f.ground ? -1 : int32_t(i);
    best.normal = n;
    best.reflectivity = f.reflectivity;
    tlim = t0;
  }
  // Clutter: people (vertical cylinders).
  const double A = d2.squaredNorm();
  if (A > 1e-18) {
    for (size_t i = 0; i < people_.size() && i < people_pos_.size(); ++i) {
      const Eigen::Vector2d f = o2 - people_pos_[i];
      const double r = people_[i].radius;
      const double B = f.dot(d2), C = f.squaredNorm() - r * r;
      const double disc = B * B - A * C;
      if (disc < 0) continue;
      const double t = (-B - std::sqrt(disc)) / A;
      if (t <= kEps || t >= tlim) continue;
      const double z = o.z() + t * d.z();
      if (z < 0 || z > people_[i].height) continue;
      const Eigen::Vector2d n = (f + t * d2).normalized();
      best.t = t;
      best.label = Label::kClutter;
      best.element = int32_t(furniture_.size() + i);
      best.normal = Eigen::Vector3d(n.x(), n.y(), 0);
      best.reflectivity = 25;
      tlim = t;
    }
  }
  // Walls: DDA over the grid, bounded by tlim.
  if (A > 1e-18 && !walls_.empty()) {
    const double gx1 = grid_min_.x() + nx_ * cell_, gy1 = grid_min_.y() + ny_ * cell_;
    double t0 = 0, t1 = tlim;
    const double omin[2] = {grid_min_.x(), grid_min_.y()}, omax[2] = {gx1, gy1};
    bool ok = true;
    for (int k = 0; k < 2 && ok; ++k) {
      if (std::abs(d2[k]) < 1e-15) {
        if (o2[k] < omin[k] || o2[k] > omax[k]) ok = false;
        continue;
      }
      double ta = (omin[k] - o2[k]) / d2[k], tb = (omax[k] - o2[k]) / d2[k];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) ok = false;
    }
    if (ok) {
      const Eigen::Vector2d p = o2 + t0 * d2;
      int ix = std::clamp(int(std::floor((p.x() - grid_min_.x()) / cell_)), 0, nx_ - 1);
      int iy = std::clamp(int(std::floor((p.y() - grid_min_.y()) / cell_)), 0, ny_ - 1);
      const int sx = d2.x() > 0 ? 1 : -1, sy = d2.y() > 0 ? 1 : -1;
      const double tdx = std::abs(d2.x()) > 1e-15 ? cell_ / std::abs(d2.x()) : kInf;
      const double tdy = std::abs(d2.y()) > 1e-15 ? cell_ / std::abs(d2.y()) : kInf;
      double tmx = std::abs(d2.x()) > 1e-15
                       ? (grid_min_.x() + (ix + (sx > 0 ? 1 : 0)) * cell_ - o2.x()) / d2.x()
                       : kInf;
      double tmy = std::abs(d2.y()) > 1e-15
                       ? (grid_min_.y() + (iy + (sy > 0 ? 1 : 0)) * cell_ - o2.y()) / d2.y()
                       : kInf;
      Hit h;
      double wall_best = tlim;
      bool wall_hit = false;
      Hit wall_h;
      for (;;) {
        const size_t ci = size_t(iy) * nx_ + ix;
        for (uint32_t k = cell_start_[ci]; k < cell_start_[ci + 1]; ++k) {
          if (hit_wall(walls_[cell_walls_[k]], o, d, wall_best, h)) {
            wall_best = h.t;
            wall_h = h;
            wall_hit = true;
          }
        }
        const double texit = std::min(tmx, tmy);
        if (wall_best <= texit || texit >= t1) break;
        if (tmx < tmy) {
          ix += sx;
          tmx += tdx;
          if (ix < 0 || ix >= nx_) break;
        } else {
          iy += sy;
          tmy += tdy;
          if (iy < 0 || iy >= ny_) break;
        }
      }
      if (wall_hit && wall_best < tlim) {
        best = wall_h;
        tlim = wall_best;
      }
    }
  }
  if (best.t == kInf) {
    best.label = Label::kNone;
    best.element = -1;
  }
  return best;
}

double World::static_clearance(const Eigen::Vector2d& p) const {
  double d = kInf;
  nearest_element_brute_force(plan_, p, &d);
  if (plan_.elements.empty()) d = kInf;
  for (const auto& f : furniture_) {
    const double c = std::cos(f.yaw), s = std::sin(f.yaw);
    const Eigen::Vector2d rel = p - f.center;
    const Eigen::Vector2d l(c * rel.x() + s * rel.y(), -s * rel.x() + c * rel.y());
    const Eigen::Vector2d q = (l.cwiseAbs() - f.half).cwiseMax(0.0);
    d = std::min(d, q.norm());
  }
  return d;
}

}  // namespace fploc::sim
