#include "perturb_doors.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fploc::sim::detail {
namespace {

using V2 = Eigen::Vector2d;

double dist_to_path(const std::vector<V2>& path, const V2& a, const V2& b) {
  double best = std::numeric_limits<double>::infinity();
  const V2 d = b - a;
  const double L2 = std::max(d.squaredNorm(), 1e-12);
  for (const V2& p : path) {
    const double t = std::clamp((p - a).dot(d) / L2, 0.0, 1.0);
    best = std::min(best, (p - a - t * d).norm());
  }
  return best;
}

}  // namespace

void move_doors(const FloorPlan& plan, const std::vector<V2>& path, int n, double min_m, double max_m, Rng& rng,
                std::vector<Element>& cur, WorldEdit& w) {
  if (n <= 0) return;
  auto doors = find_doorways(plan);
  // Random order (deterministic per seed).
  for (size_t i = doors.size(); i > 1; --i) std::swap(doors[i - 1], doors[size_t(rng.uniform() * double(i)) % i]);
  int moved = 0;
  for (const auto& [p, q] : doors) {
    if (moved >= n) break;
    const double width = (q - p).norm();
    const V2 u = (q - p) / width;
    const V2 nrm(-u.y(), u.x());
    // Plan segment ends on the two jamb lines (through p and q, across the wall, up to 0.4 m deep: both faces
    // of a two-line wall and the jambs joining them).
    auto on_jamb = [&](const V2& x, const V2& at) { return std::abs(u.dot(x - at)) < 0.01 && std::abs(nrm.dot(x - at)) < 0.4; };
    struct End {
      int id;
      bool is_b;
      bool side_q;  // on q's jamb line
    };
    std::vector<End> ends;
    for (size_t i = 0; i < plan.elements.size(); ++i) {
      const Element& e = plan.elements[i];
      if (e.kind != ElementKind::kSegment || w.elements[i].change != ElementChange::kUnchanged) continue;
      for (bool is_b : {false, true}) {
        const V2& x = is_b ? e.b : e.a;
        if (on_jamb(x, p)) ends.push_back({int(i), is_b, false});
        else if (on_jamb(x, q)) ends.push_back({int(i), is_b, true});
      }
    }
    if (ends.empty()) continue;
    const double mag = rng.uniform(min_m, max_m);
    const double first = rng.uniform() < 0.5 ? 1.0 : -1.0;
    bool done = false;
    for (double sgn : {first, -first}) {
      if (done) break;
      const double d = sgn * mag;
      // Each wall face keeps >= 0.5 m; the jambs (both ends on the jamb lines) move whole.
      bool ok = true;
      for (const End& e : ends) {
        const Element& el = plan.elements[size_t(e.id)];
        const V2 other = e.is_b ? el.a : el.b;
        if (on_jamb(other, e.side_q ? q : p)) continue;  // a jamb
        const double along = u.dot((e.is_b ? el.b : el.a) - other);  // > 0: the face runs towards +u to this end
        const double len = (el.b - el.a).norm();
        if (along * d < 0 && len - std::abs(d) < 0.5) ok = false;  // the face would shrink below 0.5 m
      }
      // The opening's old part that closes must stay clear of the path (the robot may walk through the door).
      const V2 lo = d > 0 ? p : V2(q + d * u), hi = d > 0 ? V2(p + d * u) : q;
      if (!ok || dist_to_path(path, lo, hi) < 0.5 || dist_to_path(path, p + d * u, q + d * u) < 0.3) continue;
      std::vector<int> touched;
      for (const End& e : ends) {
        Element& c = cur[size_t(e.id)];
        (e.is_b ? c.b : c.a) += d * u;
        if (std::find(touched.begin(), touched.end(), e.id) == touched.end()) touched.push_back(e.id);
      }
      for (int id : touched) w.elements[size_t(id)].change = ElementChange::kDoorMoved;
      DoorMovedTruth t;
      t.from_a = p, t.from_b = q;
      t.to_a = p + d * u, t.to_b = q + d * u;
      t.shift_m = d;
      t.elements = touched;
      // What closed (old opening not in the new one) and what opened (new opening not in the old one),
      // along the inner face (p - q's line).
      const double w0 = 0, w1 = width, n0 = d, n1 = width + d;
      t.closed_a = p + std::max(w0, std::min(w1, d > 0 ? w0 : n1)) * u;
      t.closed_b = p + std::min(w1, std::max(w0, d > 0 ? n0 : w1)) * u;
      t.opened_a = p + (d > 0 ? std::max(n0, w1) : n0) * u;
      t.opened_b = p + (d > 0 ? n1 : std::min(n1, w0)) * u;
      w.doors_moved.push_back(t);
      done = true;
    }
    if (done) ++moved;
  }
}

}  // namespace fploc::sim::detail
