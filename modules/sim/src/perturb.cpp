#include "fploc/sim/perturb.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "fploc/floorplan/io.h"
#include "fploc/core/rng.h"
#include "fploc/core/segment2d.h"
#include "perturb_doors.h"

namespace fploc::sim {
namespace {

using V2 = Eigen::Vector2d;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool blocks(const Element& e, const V2& p, const V2& q) {
  if (e.kind == ElementKind::kSegment) return segments_cross(p, q, e.a, e.b, 1e-6);
  // Circles and arcs: the closest point of p-q to the centre within the radius (arcs as full circles).
  const V2 d = q - p;
  const double t = std::clamp((e.c - p).dot(d) / std::max(d.squaredNorm(), 1e-12), 0.0, 1.0);
  return (p + t * d - e.c).norm() < e.r && (p - e.c).norm() > e.r && (q - e.c).norm() > e.r;
}

bool line_of_sight(const FloorPlan& plan, const V2& p, const V2& q, int skip, int skip2 = -1) {
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    if (int(i) == skip || int(i) == skip2) continue;
    if (blocks(plan.elements[i], p, q)) return false;
  }
  return true;
}

double seg_len(const Element& e) { return (e.b - e.a).norm(); }
V2 midpoint(const Element& e) { return e.kind == ElementKind::kSegment ? V2(0.5 * (e.a + e.b)) : e.c; }

double dist_to_points(const std::vector<V2>& pts, const V2& p) {
  double d = kInf;
  for (const auto& q : pts) d = std::min(d, (q - p).squaredNorm());
  return std::sqrt(d);
}

// The element is seen from the path: its midpoint (or, for long walls, one of 5 points) has a line of
// sight from some path point within 12 m.
bool visible_from_path(const FloorPlan& plan, int id, const std::vector<V2>& path) {
  const Element& e = plan.elements[size_t(id)];
  std::vector<V2> probes;
  if (e.kind == ElementKind::kSegment) {
    const V2 n = V2(-(e.b - e.a).y(), (e.b - e.a).x()).normalized();
    for (double f : {0.1, 0.3, 0.5, 0.7, 0.9})
      for (double side : {1.0, -1.0}) probes.push_back(e.a + f * (e.b - e.a) + side * 0.01 * n);
  } else {
    for (int k = 0; k < 8; ++k) probes.push_back(e.c + (e.r + 0.01) * V2(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4)));
  }
  for (size_t k = 0; k < path.size(); k += 5)
    for (const auto& q : probes)
      if ((path[k] - q).norm() < 12 && line_of_sight(plan, path[k], q, id)) return true;
  return false;
}

}  // namespace

// The other face of a wall drawn with two lines: a parallel segment within 0.4 m overlapping it.
int other_face(const FloorPlan& plan, int id) {
  const Element& e = plan.elements[size_t(id)];
  if (e.kind != ElementKind::kSegment) return -1;
  const V2 u = (e.b - e.a).normalized();
  const double len = seg_len(e);
  int best = -1;
  double best_d = 0.4;
  for (size_t j = 0; j < plan.elements.size(); ++j) {
    const Element& f = plan.elements[j];
    if (int(j) == id || f.kind != ElementKind::kSegment || seg_len(f) < 1e-6) continue;
    const V2 v = (f.b - f.a).normalized();
    if (std::abs(cross2(u, v)) > 0.05) continue;
    const double d = std::abs(cross2(u, midpoint(f) - e.a));
    if (d < 0.02 || d >= best_d) continue;
    double s0 = u.dot(f.a - e.a), s1 = u.dot(f.b - e.a);
    if (s0 > s1) std::swap(s0, s1);
    const double overlap = std::min(s1, len) - std::max(s0, 0.0);
    if (overlap < 0.5 * std::min(len, s1 - s0)) continue;
    best = int(j);
    best_d = d;
  }
  return best;
}

namespace {

int twin_of(const FloorPlan& plan, int id) { return other_face(plan, id); }

V2 left_normal(const V2& a, const V2& b) {
  const V2 d = (b - a).normalized();
  return V2(-d.y(), d.x());
}

V2 read_xy(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number())
    throw std::runtime_error(where + ": expected [x, y]");
  return V2(j[0].get<double>(), j[1].get<double>());
}

double read_num(const nlohmann::json& o, const char* key, double def, const std::string& where) {
  if (!o.contains(key)) return def;
  if (!o[key].is_number()) throw std::runtime_error(where + "." + key + ": expected a number");
  return o[key].get<double>();
}

double read_required_num(const nlohmann::json& o, const char* key, const std::string& where) {
  if (!o.contains(key)) throw std::runtime_error(where + "." + key + ": missing (a number is required)");
  return read_num(o, key, 0, where);
}

// An object's keys must be among `allowed`: the first other one is an error naming it and the allowed keys.
void check_keys(const nlohmann::json& o, const std::string& where, std::initializer_list<const char*> allowed) {
  if (!o.is_object()) return;
  for (auto it = o.begin(); it != o.end(); ++it) {
    if (std::any_of(allowed.begin(), allowed.end(), [&](const char* k) { return it.key() == k; })) continue;
    std::string list;
    for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
    throw std::runtime_error(where + "." + it.key() + ": unknown key (allowed: " + list + ")");
  }
}

// Fills offsets / shifts / rotation of the elements still present by comparing world and plan geometry.
void measure(const FloorPlan& plan, const std::vector<int>& world_of_plan, const FloorPlan& world, WorldEdit& w) {
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    ElementTruth& t = w.elements[i];
    const int wi = world_of_plan[i];
    if (wi < 0) continue;
    const Element& p = plan.elements[i];
    const Element& q = world.elements[size_t(wi)];
    if (p.kind == ElementKind::kSegment) {
      const V2 n = left_normal(p.a, p.b);
      t.offset_m = 0.5 * (n.dot(q.a - p.a) + n.dot(q.b - p.b));
      t.max_shift_m = std::max((q.a - p.a).norm(), (q.b - p.b).norm());
      const V2 dp = p.b - p.a, dq = q.b - q.a;
      t.rotation_rad = std::atan2(cross2(dp, dq), dp.dot(dq));
    } else {
      t.offset_m = (q.c - p.c).norm();
      t.max_shift_m = t.offset_m + std::abs(q.r - p.r);
    }
  }
}

}  // namespace

const char* change_name(ElementChange c) {
  switch (c) {
    case ElementChange::kUnchanged: return "unchanged";
    case ElementChange::kMoved: return "moved";
    case ElementChange::kRemoved: return "removed";
    case ElementChange::kGlass: return "glass";
    case ElementChange::kDoorMoved: return "door-moved";
  }
  return "?";
}

std::vector<std::string> perturb_family_names() {
  return {"clean", "asbuilt-2cm", "asbuilt-5cm", "scale-0.5pct", "renovated", "glass", "shelves", "doors", "crowd-15", "mixed",
          "doors-moved"};
}

PerturbOptions perturb_family(const std::string& name) {
  PerturbOptions o;
  o.name = name;
  if (name == "clean") return o;
  if (name == "asbuilt-2cm") o.asbuilt_sigma_m = 0.02;
  else if (name == "asbuilt-5cm") o.asbuilt_sigma_m = 0.05;
  else if (name == "scale-0.5pct") o.scale = 0.005;
  else if (name == "renovated") { o.remove = 2; o.add = 2; o.move = 2; }
  else if (name == "glass") o.glass = 0.33;
  else if (name == "shelves") o.shelves = 0.3;
  else if (name == "doors") o.doors = true;
  else if (name == "crowd-15") o.crowd = 15;
  else if (name == "doors-moved") o.doors_moved = 2;
  else if (name == "mixed") {
    o.asbuilt_sigma_m = 0.02; o.remove = 1; o.add = 1; o.move = 1; o.glass = 0.15; o.doors = true; o.shelves = 0.15; o.crowd = 8;
  } else {
    std::string all;
    for (const auto& n : perturb_family_names()) all += (all.empty() ? "" : ", ") + n;
    throw std::runtime_error("unknown world family '" + name + "' (families: " + all + ")");
  }
  return o;
}

namespace {
bool is_count(double x) { return x >= 0 && x == std::floor(x) && x < 1000; }
}  // namespace

const std::vector<PerturbKey>& perturb_keys() {
  static const std::vector<PerturbKey> keys = {
      {"asbuilt", "every wall end and pillar displaced N(0, sigma m) per axis", "a sigma in metres 0..1",
       [](double x) { return x >= 0 && x < 1; }, [](PerturbOptions& o, double x) { o.asbuilt_sigma_m = x; }},
      {"scale", "world = (1 + s) x plan (0.005: the drawing 0.5 % too small)", "a scale error -0.2..0.2",
       [](double x) { return std::abs(x) < 0.2; }, [](PerturbOptions& o, double x) { o.scale = x; }},
      {"remove", "walls (with their other face) / pillars taken out (count)", "a count", is_count,
       [](PerturbOptions& o, double x) { o.remove = int(x); }},
      {"add", "partitions added (count)", "a count", is_count, [](PerturbOptions& o, double x) { o.add = int(x); }},
      {"move", "walls moved along their normal (count)", "a count", is_count,
       [](PerturbOptions& o, double x) { o.move = int(x); }},
      {"move_min", "least wall move, m (0.10)", "metres 0..2", [](double x) { return x > 0 && x < 2; },
       [](PerturbOptions& o, double x) { o.move_min_m = x; }},
      {"move_max", "largest wall move, m (0.25)", "metres 0..2", [](double x) { return x > 0 && x < 2; },
       [](PerturbOptions& o, double x) { o.move_max_m = x; }},
      {"glass", "fraction of the visible wall length turned to glass", "a fraction 0..1",
       [](double x) { return x >= 0 && x <= 1; }, [](PerturbOptions& o, double x) { o.glass = x; }},
      {"doors", "door leaves in the doorways, open or closed (0/1)", "0 or 1", [](double x) { return x == 0 || x == 1; },
       [](PerturbOptions& o, double x) { o.doors = x == 1; }},
      {"shelves", "fraction of the wall length behind 2 m shelving", "a fraction 0..1",
       [](double x) { return x >= 0 && x <= 1; }, [](PerturbOptions& o, double x) { o.shelves = x; }},
      {"crowd", "people walking near the path (count)", "a count", is_count,
       [](PerturbOptions& o, double x) { o.crowd = int(x); }},
      {"doors_moved", "doorways shifted along their wall (count)", "a count", is_count,
       [](PerturbOptions& o, double x) { o.doors_moved = int(x); }},
      {"door_shift_min", "least doorway shift, m (0.4)", "metres 0..5", [](double x) { return x > 0 && x < 5; },
       [](PerturbOptions& o, double x) { o.door_shift_min_m = x; }},
      {"door_shift_max", "largest doorway shift, m (0.9)", "metres 0..5", [](double x) { return x > 0 && x < 5; },
       [](PerturbOptions& o, double x) { o.door_shift_max_m = x; }},
  };
  return keys;
}

std::string perturb_keys_help() {
  std::string s;
  for (const auto& k : perturb_keys()) s += (s.empty() ? "" : "; ") + std::string(k.name) + ": " + k.doc;
  return s;
}

PerturbOptions parse_perturb(const std::string& spec) {
  if (spec.find('=') == std::string::npos) return perturb_family(spec);
  PerturbOptions o;
  o.name = spec;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw std::runtime_error("--perturb: '" + item + "': expected key=value");
    const std::string k = item.substr(0, eq), v = item.substr(eq + 1);
    double x = 0;
    try {
      size_t used = 0;
      x = std::stod(v, &used);
      if (used != v.size()) throw std::invalid_argument(v);
    } catch (const std::exception&) {
      throw std::runtime_error("--perturb: " + k + "='" + v + "': expected a number");
    }
    const auto& keys = perturb_keys();
    const auto it = std::find_if(keys.begin(), keys.end(), [&](const PerturbKey& pk) { return k == pk.name; });
    if (it == keys.end()) {
      std::string all;
      for (const auto& pk : keys) all += (all.empty() ? "" : ", ") + std::string(pk.name);
      throw std::runtime_error("--perturb: unknown key '" + k + "' (keys: " + all + ")");
    }
    if (!it->ok(x)) throw std::runtime_error("--perturb: " + k + "=" + v + ": expected " + it->expected);
    it->set(o, x);
  }
  if (o.move_max_m < o.move_min_m) throw std::runtime_error("--perturb: move_max < move_min");
  if (o.door_shift_max_m < o.door_shift_min_m) throw std::runtime_error("--perturb: door_shift_max < door_shift_min");
  return o;
}

std::vector<std::pair<V2, V2>> find_doorways(const FloorPlan& plan) {
  std::vector<std::pair<V2, V2>> out;
  const auto& el = plan.elements;
  for (size_t i = 0; i < el.size(); ++i) {
    if (el[i].kind != ElementKind::kSegment || seg_len(el[i]) < 0.3) continue;
    for (size_t j = i + 1; j < el.size(); ++j) {
      if (el[j].kind != ElementKind::kSegment || seg_len(el[j]) < 0.3) continue;
      const V2 u = (el[i].b - el[i].a).normalized(), v = (el[j].b - el[j].a).normalized();
      if (std::abs(cross2(u, v)) > 0.02) continue;
      for (const V2& p : {el[i].a, el[i].b})
        for (const V2& q : {el[j].a, el[j].b}) {
          const double w = (q - p).norm();
          if (w < 0.7 || w > 1.3) continue;
          if (std::abs(cross2(u, (q - p) / w)) > 0.02) continue;  // not collinear: a gap across, not along
          // Both ends must be the segments' outer ends (the gap lies outside both segments).
          const V2 ci = midpoint(el[i]), cj = midpoint(el[j]);
          if ((q - p).dot(p - ci) <= 0 || (p - q).dot(q - cj) <= 0) continue;
          bool dup = false;
          for (const auto& d : out)
            if ((0.5 * (d.first + d.second) - 0.5 * (p + q)).norm() < 0.45) dup = true;
          if (!dup) out.emplace_back(p, q);
        }
    }
  }
  return out;
}

WorldEdit perturb_world(const FloorPlan& plan, const std::vector<V2>& path, const PerturbOptions& o, uint64_t seed) {
  WorldEdit w;
  w.source = o.name;
  w.seed = seed;
  w.scale = o.scale;
  w.asbuilt_sigma_m = o.asbuilt_sigma_m;
  w.wall_clutter = o.shelves;
  const size_t n = plan.elements.size();
  w.elements.assign(n, {});
  std::vector<Element> cur = plan.elements;  // world geometry of each plan element
  const Box2 bb = plan.bounds();
  const V2 centre = 0.5 * (bb.min + bb.max);

  // As-built: shared wall ends move together (walls stay joined), pillars as a whole.
  if (o.asbuilt_sigma_m > 0) {
    Rng rng(mix_seed(seed, 0xA5B1u));
    std::map<std::pair<long, long>, V2> shift;
    auto key = [](const V2& p) { return std::make_pair(std::lround(p.x() * 1000), std::lround(p.y() * 1000)); };
    auto disp = [&](const V2& p) -> V2 {
      auto [it, fresh] = shift.try_emplace(key(p), V2::Zero());
      if (fresh) it->second = V2(rng.normal(o.asbuilt_sigma_m), rng.normal(o.asbuilt_sigma_m));
      return it->second;
    };
    for (auto& e : cur) {
      if (e.kind == ElementKind::kSegment) {
        e.a += disp(e.a);
        e.b += disp(e.b);
      } else {
        e.c += V2(rng.normal(o.asbuilt_sigma_m), rng.normal(o.asbuilt_sigma_m));
      }
    }
  }

  Rng rng(mix_seed(seed, 0x4E70u));
  std::vector<int> visible;
  if (o.remove || o.move || o.glass > 0)
    for (size_t i = 0; i < n; ++i)
      if ((plan.elements[i].kind != ElementKind::kSegment || seg_len(plan.elements[i]) >= 1.0) &&
          visible_from_path(plan, int(i), path))
        visible.push_back(int(i));
  auto shuffled = [&](std::vector<int> v) {
    for (size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[size_t(rng.uniform() * double(i)) % i]);
    return v;
  };
  auto take = [&](int id, ElementChange c) {
    w.elements[size_t(id)].change = c;
    const int t = twin_of(plan, id);
    if (t >= 0 && w.elements[size_t(t)].change == ElementChange::kUnchanged) w.elements[size_t(t)].change = c;
  };
  auto free_el = [&](int id) {
    const int t = twin_of(plan, id);
    return w.elements[size_t(id)].change == ElementChange::kUnchanged &&
           (t < 0 || w.elements[size_t(t)].change == ElementChange::kUnchanged);
  };

  // Renovation: walls removed (with their other face) and pillars removed.
  int removed = 0;
  for (int id : shuffled(visible)) {
    if (removed >= o.remove) break;
    const Element& e = plan.elements[size_t(id)];
    if (!free_el(id) || (e.kind == ElementKind::kSegment && seg_len(e) < 1.5)) continue;
    take(id, ElementChange::kRemoved);
    ++removed;
  }
  // Renovation: walls moved by move_min..move_max along their normal (away from or towards the path,
  // keeping 0.5 m of clearance).
  int moved = 0;
  for (int id : shuffled(visible)) {
    if (moved >= o.move) break;
    const Element& e = plan.elements[size_t(id)];
    if (!free_el(id) || e.kind != ElementKind::kSegment || seg_len(e) < 1.5) continue;
    const double mag = rng.uniform(o.move_min_m, o.move_max_m);
    const V2 nrm = left_normal(e.a, e.b);
    const int twin = twin_of(plan, id);
    bool done = false;
    const double first = rng.uniform() < 0.5 ? 1.0 : -1.0;
    for (double s : {first, -first}) {
      if (done) break;
      const V2 dv = s * mag * nrm;
      std::vector<V2> pts;
      for (int k = 0; k <= 20; ++k) pts.push_back(cur[size_t(id)].a + dv + (k / 20.0) * (cur[size_t(id)].b - cur[size_t(id)].a));
      double clr = kInf;
      for (const auto& p : pts) clr = std::min(clr, dist_to_points(path, p));
      if (clr < 0.5) continue;
      for (int j : {id, twin}) {
        if (j < 0) continue;
        cur[size_t(j)].a += dv;
        cur[size_t(j)].b += dv;
        w.elements[size_t(j)].change = ElementChange::kMoved;
      }
      done = true;
    }
    if (done) ++moved;
  }
  // Glass: visible walls, in random order, until the fraction of the visible wall length is reached.
  if (o.glass > 0) {
    double total = 0, glass = 0;
    for (int id : visible)
      if (plan.elements[size_t(id)].kind == ElementKind::kSegment) total += seg_len(plan.elements[size_t(id)]);
    for (int id : shuffled(visible)) {
      if (glass >= o.glass * total) break;
      if (plan.elements[size_t(id)].kind != ElementKind::kSegment || !free_el(id)) continue;
      take(id, ElementChange::kGlass);
      glass += seg_len(plan.elements[size_t(id)]);
    }
  }

  // Renovation: doorways moved along their wall (own random stream: the other perturbations stay as they were).
  if (o.doors_moved > 0) {
    Rng drng(mix_seed(seed, 0xD00Bu));
    detail::move_doors(plan, path, o.doors_moved, o.door_shift_min_m, o.door_shift_max_m, drng, cur, w);
  }

  // The world: plan elements that are still there (their world geometry), then what was added.
  FloorPlan& wp = w.world;
  wp.layers = plan.layers;
  wp.source = plan.source;
  std::vector<int> world_of_plan(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const auto c = w.elements[i].change;
    if (c == ElementChange::kRemoved || c == ElementChange::kGlass) continue;
    world_of_plan[i] = int(wp.elements.size());
    wp.elements.push_back(cur[i]);
  }
  // Partitions: 1.2-3 m, axis-aligned with the plan's dominant directions (those of its longest wall),
  // 0.8 m from the path and 0.3 m from everything else.
  if (o.add > 0) {
    V2 dir(1, 0);
    double longest = 0;
    for (const auto& e : plan.elements)
      if (e.kind == ElementKind::kSegment && seg_len(e) > longest) longest = seg_len(e), dir = (e.b - e.a).normalized();
    const int layer = wp.layer_index("partition");
    int added = 0;
    for (int attempt = 0; attempt < 2000 && added < o.add; ++attempt) {
      const V2 c(rng.uniform(bb.min.x() + 0.5, bb.max.x() - 0.5), rng.uniform(bb.min.y() + 0.5, bb.max.y() - 0.5));
      const V2 u = rng.uniform() < 0.5 ? dir : V2(-dir.y(), dir.x());
      const double len = rng.uniform(1.2, 3.0);
      const V2 a = c - 0.5 * len * u, b = c + 0.5 * len * u;
      bool ok = true;
      for (int k = 0; k <= 30 && ok; ++k) {
        const V2 p = a + (k / 30.0) * (b - a);
        double d = kInf;
        nearest_element_brute_force(wp, p, &d);
        if (d < 0.3 || dist_to_points(path, p) < 0.8) ok = false;
      }
      // Inside the building: something of the plan in all four directions.
      for (const V2& dd : {V2(1, 0), V2(-1, 0), V2(0, 1), V2(0, -1)})
        if (ok && line_of_sight(plan, c, c + 100 * dd, -1)) ok = false;
      // ... and where the robot can see it: lines of sight from 10 points of the path within 12 m (as
      // visible_from_path; several, so a ray slipping through a joint of two walls does not count). A partition
      // inside a corridor loop's walled-in core is no renovation anyone could find.
      if (ok) {
        int seen = 0;
        for (size_t k = 0; k < path.size() && seen < 10; k += 5)
          if ((path[k] - c).norm() < 12 && line_of_sight(wp, path[k], c, -1)) ++seen;
        ok = seen >= 10;
      }
      if (!ok) continue;
      wp.elements.push_back(Element::segment(a, b, layer));
      w.added.push_back({"partition", a, b});
      ++added;
    }
  }
  // Doors in the plan's doorways: closed (a leaf across the gap) or open (a leaf hinged at one end,
  // turned 90 degrees to the side away from the path).
  if (o.doors) {
    const int layer = wp.layer_index("door");
    for (const auto& [a, b] : find_doorways(plan)) {
      const bool open = rng.uniform() < 0.5;
      V2 p = a, q = b;
      std::string kind = "door-closed";
      if (open) {
        const V2 nrm = left_normal(a, b);
        const double len = (b - a).norm();
        const V2 q1 = a + len * nrm, q2 = a - len * nrm;
        const V2 mid = 0.5 * (a + b);
        const double c1 = dist_to_points(path, 0.5 * (a + q1)), c2 = dist_to_points(path, 0.5 * (a + q2));
        q = c1 > c2 ? q1 : q2;
        if (std::min(dist_to_points(path, q), dist_to_points(path, mid)) < 0.5) q = b;  // would hit the path: closed
        else kind = "door-open";
      }
      if ((dist_to_points(path, 0.5 * (p + q))) < 0.3) continue;  // the path goes through: leave it open wide
      wp.elements.push_back(Element::segment(p, q, layer));
      w.added.push_back({kind, p, q});
    }
  }
  // Scale error: the whole world about the plan's centre.
  if (o.scale != 0) {
    const double s = 1 + o.scale;
    for (auto& e : wp.elements) {
      e.a = centre + s * (e.a - centre);
      e.b = centre + s * (e.b - centre);
      e.c = centre + s * (e.c - centre);
      e.r *= s;
    }
    for (auto& a : w.added) {
      a.a = centre + s * (a.a - centre);
      a.b = centre + s * (a.b - centre);
    }
  }
  measure(plan, world_of_plan, wp, w);
  // A crowd: people walking 2-6 m straight lines (back and forth) near the path, never on it, and where the robot
  // can see them: both ends and the middle of a person's line seen from 5 or more points of the path within 10 m
  // (lines of sight through the world's walls). Without it, on the corridor loop every person landed in the loop's
  // walled-in core or outside its outer walls (inside the plan's bounding box, 0.6 m off the path, 0.35 m off the
  // walls: the corridor's own strip beside the path is narrow), and crowd-15 was the clean world.
  if (o.crowd > 0) {
    int people = 0;
    for (int attempt = 0; attempt < 20000 && people < o.crowd; ++attempt) {
      const V2 base = path[size_t(rng.uniform() * double(path.size())) % path.size()];
      const double ang = rng.uniform(0, 2 * M_PI), r = rng.uniform(0.8, 5.0);
      const V2 p0 = base + r * V2(std::cos(ang), std::sin(ang));
      const double b = rng.uniform(0, 2 * M_PI), len = rng.uniform(2.0, 6.0);
      const V2 p1 = p0 + len * V2(std::cos(b), std::sin(b));
      bool ok = true;
      for (int k = 0; k <= 20 && ok; ++k) {
        const V2 q = p0 + (k / 20.0) * (p1 - p0);
        double d = kInf;
        nearest_element_brute_force(wp, q, &d);
        if (d < 0.35 || dist_to_points(path, q) < 0.6 || q.x() < bb.min.x() || q.y() < bb.min.y() || q.x() > bb.max.x() ||
            q.y() > bb.max.y())
          ok = false;
      }
      for (const V2& q : {p0, V2(0.5 * (p0 + p1)), p1}) {
        int seen = 0;
        for (size_t k = 0; ok && k < path.size() && seen < 5; k += 5)
          if ((path[k] - q).norm() < 10 && line_of_sight(wp, path[k], q, -1)) ++seen;
        ok = ok && seen >= 5;
      }
      if (!ok) continue;
      Person p;
      p.path = {p0, p1};
      p.speed = rng.uniform(0.5, 1.4);
      p.phase_s = rng.uniform(0, 20);
      w.people.push_back(p);
      ++people;
    }
  }
  return w;
}

std::string WorldEdit::truth_json(const FloorPlan& plan) const {
  nlohmann::json j;
  j["source"] = source;
  j["seed"] = seed;
  j["scale"] = scale;
  j["asbuilt_sigma_m"] = asbuilt_sigma_m;
  j["plan"] = plan.source;
  j["plan_elements"] = plan.elements.size();
  double wall_len = 0;
  for (const auto& e : plan.elements)
    if (e.kind == ElementKind::kSegment) wall_len += seg_len(e);
  j["plan_wall_length_m"] = wall_len;
  auto& el = j["elements"] = nlohmann::json::array();
  for (size_t i = 0; i < elements.size() && i < plan.elements.size(); ++i) {
    const auto& t = elements[i];
    const auto& e = plan.elements[i];
    el.push_back({{"id", i},
                  {"change", change_name(t.change)},
                  {"kind", e.kind == ElementKind::kSegment ? "segment" : e.kind == ElementKind::kCircle ? "circle" : "arc"},
                  {"offset_m", t.offset_m},
                  {"max_shift_m", t.max_shift_m},
                  {"rotation_deg", t.rotation_rad * 180 / M_PI},
                  {"length_m", e.kind == ElementKind::kSegment ? seg_len(e) : 2 * M_PI * e.r}});
  }
  auto& ad = j["added"] = nlohmann::json::array();
  for (const auto& a : added)
    ad.push_back({{"kind", a.kind}, {"a", {a.a.x(), a.a.y()}}, {"b", {a.b.x(), a.b.y()}}, {"length_m", (a.b - a.a).norm()}});
  auto& dm = j["doors_moved"] = nlohmann::json::array();
  auto seg = [](const V2& a, const V2& b) { return nlohmann::json::array({{a.x(), a.y()}, {b.x(), b.y()}}); };
  for (const auto& d : doors_moved)
    dm.push_back({{"from", seg(d.from_a, d.from_b)}, {"to", seg(d.to_a, d.to_b)}, {"closed", seg(d.closed_a, d.closed_b)},
                  {"opened", seg(d.opened_a, d.opened_b)}, {"shift_m", d.shift_m}, {"elements", d.elements}});
  j["shelves_fraction"] = wall_clutter;
  j["shelves"] = furniture.size();
  j["people"] = people.size();
  return j.dump(1);
}

WorldEdit load_world_file(const std::string& path, const FloorPlan& plan, const std::vector<std::string>& layers,
                          const std::string& units) {
  auto ext = path.substr(path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  WorldEdit w;
  w.source = path;
  w.elements.assign(plan.elements.size(), {});
  nlohmann::json j;
  if (ext == ".json") {
    std::ifstream in(path);
    if (!in) throw std::runtime_error(path + ": cannot read the world file");
    try {
      j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
      std::string what = e.what();
      const auto p = what.find("parse error");
      throw std::runtime_error(path + ": byte " + std::to_string(e.byte) + ": JSON syntax error (" +
                               (p == std::string::npos ? what : what.substr(p)) + ")");
    }
  }
  if (!j.is_object() || !j.contains("world")) {
    // Any plan file: these are the world's walls.
    w.world = load_floor_plan(path, layers, units);
    w.elements.clear();  // no per-element correspondence to the plan
    return w;
  }
  const auto& o = j["world"];
  if (!o.is_object()) throw std::runtime_error(path + ": world: expected an object");
  check_keys(o, path + ": world", {"plan", "remove", "glass", "move", "add", "doors", "shelves", "people"});
  FloorPlan base = plan;
  if (o.contains("plan")) {
    if (!o["plan"].is_string()) throw std::runtime_error(path + ": world.plan: expected a file name");
    std::string p = o["plan"].get<std::string>();
    const auto slash = path.find_last_of('/');
    if (!p.empty() && p[0] != '/' && slash != std::string::npos) p = path.substr(0, slash + 1) + p;
    base = load_floor_plan(p, layers, units);
    if (base.elements.size() != plan.elements.size())
      w.elements.assign(base.elements.size(), {});
  }
  // Plan elements named in remove / glass / move. A wall drawn with two lines (two faces) changes as a whole,
  // as with --perturb: the other face (other_face()) takes the same change (and the same displacement) unless
  // it is named itself.
  std::vector<bool> named(base.elements.size(), false);
  std::vector<V2> shift(base.elements.size(), V2::Zero());
  auto ids = [&](const char* key, ElementChange c) {
    if (!o.contains(key)) return;
    if (!o[key].is_array()) throw std::runtime_error(path + ": world." + key + ": expected a list of element ids");
    for (size_t i = 0; i < o[key].size(); ++i) {
      const auto& v = o[key][i];
      const std::string where = path + ": world." + key + "[" + std::to_string(i) + "]";
      if (!v.is_number_integer() || v.get<long>() < 0 || v.get<size_t>() >= base.elements.size())
        throw std::runtime_error(where + ": expected an element id 0.." + std::to_string(base.elements.size() - 1));
      w.elements[v.get<size_t>()].change = c;
      named[v.get<size_t>()] = true;
    }
  };
  ids("remove", ElementChange::kRemoved);
  ids("glass", ElementChange::kGlass);
  std::vector<Element> cur = base.elements;
  if (o.contains("move")) {
    if (!o["move"].is_array()) throw std::runtime_error(path + ": world.move: expected a list");
    for (size_t i = 0; i < o["move"].size(); ++i) {
      const auto& m = o["move"][i];
      const std::string where = path + ": world.move[" + std::to_string(i) + "]";
      if (!m.is_object()) throw std::runtime_error(where + ": expected an object {\"id\": N, \"offset_m\": metres}");
      check_keys(m, where, {"id", "offset_m"});
      if (!m.contains("id") || !m["id"].is_number_integer() || m["id"].get<long>() < 0 ||
          m["id"].get<size_t>() >= base.elements.size() || base.elements[m["id"].get<size_t>()].kind != ElementKind::kSegment)
        throw std::runtime_error(where + ".id: expected the id of a segment");
      const size_t id = m["id"].get<size_t>();
      if (w.elements[id].change == ElementChange::kMoved)
        throw std::runtime_error(where + ".id: element " + std::to_string(id) + " is moved twice (one entry per element)");
      const double off = read_required_num(m, "offset_m", where);
      shift[id] = off * left_normal(cur[id].a, cur[id].b);
      w.elements[id].change = ElementChange::kMoved;
      named[id] = true;
    }
  }
  std::vector<ElementChange> explicit_change(base.elements.size());
  for (size_t i = 0; i < base.elements.size(); ++i) explicit_change[i] = w.elements[i].change;
  for (size_t i = 0; i < base.elements.size(); ++i) {
    if (!named[i]) continue;
    const int t = other_face(base, int(i));
    if (t < 0 || named[size_t(t)] || w.elements[size_t(t)].change != ElementChange::kUnchanged) continue;
    w.elements[size_t(t)].change = explicit_change[i];
    shift[size_t(t)] = shift[i];
  }
  for (size_t i = 0; i < base.elements.size(); ++i) {
    cur[i].a += shift[i];
    cur[i].b += shift[i];
  }
  w.world.layers = base.layers;
  w.world.source = path;
  std::vector<int> world_of_plan(base.elements.size(), -1);
  for (size_t i = 0; i < base.elements.size(); ++i) {
    if (w.elements[i].change == ElementChange::kRemoved || w.elements[i].change == ElementChange::kGlass) continue;
    world_of_plan[i] = int(w.world.elements.size());
    w.world.elements.push_back(cur[i]);
  }
  auto segs = [&](const char* key, std::initializer_list<const char*> allowed,
                  const std::function<void(const nlohmann::json&, const V2&, const V2&, const std::string&)>& f) {
    if (!o.contains(key)) return;
    if (!o[key].is_array()) throw std::runtime_error(path + ": world." + key + ": expected a list");
    for (size_t i = 0; i < o[key].size(); ++i) {
      const auto& v = o[key][i];
      const std::string where = path + ": world." + key + "[" + std::to_string(i) + "]";
      if (!v.is_object()) throw std::runtime_error(where + ": expected an object");
      check_keys(v, where, allowed);
      if (!v.contains("a") || !v.contains("b")) throw std::runtime_error(where + ": needs \"a\" and \"b\"");
      const V2 a = read_xy(v["a"], where + ".a"), b = read_xy(v["b"], where + ".b");
      if ((b - a).norm() < 1e-3) throw std::runtime_error(where + ": a and b coincide");
      f(v, a, b, where);
    }
  };
  segs("add", {"a", "b"}, [&](const nlohmann::json&, const V2& a, const V2& b, const std::string&) {
    w.world.elements.push_back(Element::segment(a, b, w.world.layer_index("partition")));
    w.added.push_back({"partition", a, b});
  });
  segs("doors", {"a", "b", "open"}, [&](const nlohmann::json& v, const V2& a, const V2& b, const std::string& where) {
    if (v.contains("open") && !v["open"].is_boolean()) throw std::runtime_error(where + ".open: expected true or false");
    const bool open = v.value("open", false);
    const V2 q = open ? V2(a + (b - a).norm() * left_normal(a, b)) : b;
    w.world.elements.push_back(Element::segment(a, q, w.world.layer_index("door")));
    w.added.push_back({open ? "door-open" : "door-closed", a, q});
  });
  segs("shelves", {"a", "b", "depth", "height"}, [&](const nlohmann::json& v, const V2& a, const V2& b, const std::string& where) {
    Furniture f;
    const double depth = read_num(v, "depth", 0.4, where), height = read_num(v, "height", 2.0, where);
    if (!(depth > 0 && height > 0)) throw std::runtime_error(where + ": depth and height must be positive");
    f.center = 0.5 * (a + b) + (0.5 * depth + 0.02) * left_normal(a, b);
    f.yaw = std::atan2((b - a).y(), (b - a).x());
    f.half = V2(0.5 * (b - a).norm(), 0.5 * depth);
    f.z1 = height;
    f.reflectivity = 35;
    w.furniture.push_back(f);
  });
  if (o.contains("people")) {
    if (!o["people"].is_array()) throw std::runtime_error(path + ": world.people: expected a list");
    for (size_t i = 0; i < o["people"].size(); ++i) {
      const auto& v = o["people"][i];
      const std::string where = path + ": world.people[" + std::to_string(i) + "]";
      check_keys(v, where, {"path", "speed"});
      if (!v.is_object() || !v.contains("path") || !v["path"].is_array() || v["path"].empty())
        throw std::runtime_error(where + ".path: expected a list of [x, y] points");
      Person p;
      for (size_t k = 0; k < v["path"].size(); ++k) p.path.push_back(read_xy(v["path"][k], where + ".path[" + std::to_string(k) + "]"));
      p.speed = read_num(v, "speed", 1.0, where);
      w.people.push_back(p);
    }
  }
  measure(base, world_of_plan, w.world, w);
  return w;
}

}  // namespace fploc::sim
