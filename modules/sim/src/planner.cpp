#include "fploc/sim/planner.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "fploc/sim/motion.h"

namespace fploc::sim {
namespace {

using V = Eigen::Vector2d;
constexpr double kBig = 1e20;
constexpr double kOpenR = 0.5;
constexpr double kMinRadius = 0.6;

// 1D squared distance transform (Felzenszwalb & Huttenlocher).
void dt1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v, std::vector<double>& z) {
  const int n = int(f.size());
  int k = 0;
  v[0] = 0;
  z[0] = -kBig;
  z[1] = kBig;
  auto inter = [&](int q, int p) {
    return ((f[size_t(q)] + double(q) * q) - (f[size_t(p)] + double(p) * p)) / (2.0 * q - 2.0 * p);
  };
  for (int q = 1; q < n; ++q) {
    double s = inter(q, v[size_t(k)]);
    while (s <= z[size_t(k)]) {
      --k;
      s = inter(q, v[size_t(k)]);
    }
    ++k;
    v[size_t(k)] = q;
    z[size_t(k)] = s;
    z[size_t(k) + 1] = kBig;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[size_t(k) + 1] < q) ++k;
    const int p = v[size_t(k)];
    d[size_t(q)] = double(q - p) * (q - p) + f[size_t(p)];
  }
}

// 2D squared EDT (in cells^2) of f (0 = occupied, kBig = free): columns then rows.
std::vector<double> edt(std::vector<double> f, int nx, int ny) {
  const int m = std::max(nx, ny);
  std::vector<double> col, d(static_cast<size_t>(m)), zz(static_cast<size_t>(m) + 1);
  std::vector<int> vv(static_cast<size_t>(m));
  for (int x = 0; x < nx; ++x) {
    col.resize(size_t(ny));
    d.resize(size_t(ny));
    for (int y = 0; y < ny; ++y) col[size_t(y)] = f[size_t(y) * nx + x];
    dt1d(col, d, vv, zz);
    for (int y = 0; y < ny; ++y) f[size_t(y) * nx + x] = d[size_t(y)];
  }
  for (int y = 0; y < ny; ++y) {
    col.assign(f.begin() + long(y) * nx, f.begin() + long(y + 1) * nx);
    d.resize(size_t(nx));
    dt1d(col, d, vv, zz);
    for (int x = 0; x < nx; ++x) f[size_t(y) * nx + x] = d[size_t(x)];
  }
  return f;
}

struct Grid {
  int nx = 0, ny = 0;
  double res = 0.1;
  V origin;
  std::vector<double> dist;  // metres to the nearest occupied cell centre
  V center(int ix, int iy) const { return origin + V((ix + 0.5) * res, (iy + 0.5) * res); }
};

Grid distance_grid(const FloorPlan& plan, double res, double pad) {
  Grid g;
  const Box2 b = plan.bounds();
  g.res = res;
  g.origin = b.min - V(pad, pad);
  g.nx = int(std::ceil((b.size().x() + 2 * pad) / res)) + 1;
  g.ny = int(std::ceil((b.size().y() + 2 * pad) / res)) + 1;
  std::vector<double> f(size_t(g.nx) * g.ny, kBig);
  auto mark = [&](const V& p) {
    const int ix = int(std::floor((p.x() - g.origin.x()) / res)), iy = int(std::floor((p.y() - g.origin.y()) / res));
    if (ix >= 0 && iy >= 0 && ix < g.nx && iy < g.ny) f[size_t(iy) * g.nx + ix] = 0;
  };
  for (const auto& e : plan.elements) {
    if (e.kind == ElementKind::kSegment) {
      const int n = std::max(1, int(std::ceil((e.b - e.a).norm() / (0.4 * res))));
      for (int i = 0; i <= n; ++i) mark(e.a + (e.b - e.a) * (double(i) / n));
    } else {
      const double a0 = e.kind == ElementKind::kCircle ? 0 : e.a0, a1 = e.kind == ElementKind::kCircle ? 2 * M_PI : e.a1;
      const int n = std::max(4, int(std::ceil((a1 - a0) * e.r / (0.4 * res))));
      for (int i = 0; i <= n; ++i) {
        const double a = a0 + (a1 - a0) * i / n;
        mark(e.c + e.r * V(std::cos(a), std::sin(a)));
      }
      if (e.kind == ElementKind::kCircle)  // solid pillar
        for (double r = 0; r < e.r; r += 0.4 * res)
          for (int i = 0; i < n; ++i) mark(e.c + r * V(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n)));
    }
  }
  f = edt(f, g.nx, g.ny);
  g.dist.resize(f.size());
  for (size_t i = 0; i < f.size(); ++i) g.dist[i] = std::sqrt(f[i]) * res;
  return g;
}

// Moore-neighbour tracing of the outer boundary of the component `id` in `lab` (Jacob's stopping
// criterion: stop when the start cell is left the same way as the first time).
std::vector<std::pair<int, int>> trace(const std::vector<int>& lab, int nx, int ny, int id, int sx, int sy,
                                       size_t max_steps) {
  static const int dx[8] = {-1, -1, 0, 1, 1, 1, 0, -1}, dy[8] = {0, 1, 1, 1, 0, -1, -1, -1};
  auto fg = [&](int x, int y) { return x >= 0 && y >= 0 && x < nx && y < ny && lab[size_t(y) * nx + x] == id; };
  std::vector<std::pair<int, int>> out{{sx, sy}};
  int px = sx, py = sy;
  int cdir = 6;  // backtrack: the cell below (a bottom-up scan found s first)
  int first = -1;
  for (size_t step = 0; step < max_steps; ++step) {
    int found = -1;
    for (int i = 1; i <= 8; ++i) {
      const int k = (cdir + i) % 8;
      if (fg(px + dx[k], py + dy[k])) {
        found = k;
        break;
      }
    }
    if (found < 0) break;  // isolated cell
    if (px == sx && py == sy) {
      if (first < 0) first = found;
      else if (found == first) break;
    }
    const int prev = (found + 7) % 8;  // background cell just before `found` (relative to p)
    const int bx = px + dx[prev], by = py + dy[prev];
    px += dx[found];
    py += dy[found];
    cdir = 0;
    for (int k = 0; k < 8; ++k)
      if (px + dx[k] == bx && py + dy[k] == by) cdir = k;
    out.emplace_back(px, py);
  }
  if (out.size() > 1 && out.back() == out.front()) out.pop_back();
  return out;
}

}  // namespace

double min_clearance(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& pts) {
  double m = std::numeric_limits<double>::infinity();
  for (const auto& p : pts) {
    double d = 0;
    if (nearest_element_brute_force(plan, p, &d) >= 0) m = std::min(m, d);
  }
  return m;
}

AutoLoopResult plan_auto_loop(const FloorPlan& plan, const AutoLoopConfig& cfg) {
  if (plan.elements.empty()) throw std::runtime_error("auto-loop: the plan has no elements");
  const Box2 b = plan.bounds();
  const double ext = std::max(b.size().x(), b.size().y());
  const double res = cfg.resolution_m > 0 ? cfg.resolution_m : std::clamp(ext / 1000.0, 0.05, 0.2);
  // A plan in the wrong units (a mm drawing read as metres: 52 x 23 km) asked for 3e10 cells: "fploc sim: std::bad_alloc".
  const double cells = (b.size().x() / res + 4 / res + 1) * (b.size().y() / res + 4 / res + 1);
  if (cells > 5e7) {
    std::ostringstream m;
    m << "auto-loop: " << (plan.source.empty() ? std::string("the plan") : plan.source) << " is " << std::fixed
      << std::setprecision(0) << b.size().x() << " x " << b.size().y() << " m, too large to plan a path on ("
      << std::setprecision(2) << cells / 1e6 << " million cells of " << res
      << " m); check the units (a drawing in mm or cm read as metres: --units mm)";
    throw std::runtime_error(m.str());
  }
  const Grid g = distance_grid(plan, res, 2.0);
  const double dmin = cfg.clearance_m + 0.15 + res;
  std::vector<double> offsets;
  for (double D = cfg.max_offset_m; D > dmin - 1e-9; D -= 0.15) offsets.push_back(D);
  if (offsets.empty() || offsets.back() > dmin + 1e-9) offsets.push_back(dmin);

  struct Candidate {
    double D;
    std::vector<std::pair<int, int>> boundary;
    double perimeter;
    double R;
  };
  std::vector<Candidate> cands;
  std::vector<int> lab(g.dist.size());
  // First the enclosed free space; when there is none (an open plan such as a pavilion), the free space
  // inside the plan's bounding box.
  bool bounded = false;
  for (int pass = 0; pass < 2 && cands.empty(); ++pass)
  for (const double D : offsets)
  for (const double R : {kOpenR, 0.0}) {
    bounded = pass == 1;
    // Morphological opening of {dist >= D} by a disc of radius R (removes passages narrower than 2R, so the
    // traced boundary has no thin spikes): dilate {dist >= D + R} by R.
    std::vector<uint8_t> region(g.dist.size(), 0);
    {
      std::vector<double> f(g.dist.size(), kBig);
      for (size_t i = 0; i < f.size(); ++i)
        if (g.dist[i] >= D + R) f[i] = 0;
      const std::vector<double> d2 = edt(f, g.nx, g.ny);
      for (size_t i = 0; i < f.size(); ++i) region[i] = std::sqrt(d2[i]) * res <= R + 1e-9 && g.dist[i] >= D;
      if (bounded)
        for (int y = 0; y < g.ny; ++y)
          for (int x = 0; x < g.nx; ++x) {
            const V c = g.center(x, y);
            if (c.x() < b.min.x() + D || c.y() < b.min.y() + D || c.x() > b.max.x() - D || c.y() > b.max.y() - D)
              region[size_t(y) * g.nx + x] = 0;
          }
    }
    // Components of the region that do not touch the border.
    std::fill(lab.begin(), lab.end(), -1);
    int next = 0;
    std::vector<int> stack;
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        const size_t i = size_t(y) * g.nx + x;
        if (lab[i] != -1 || !region[i]) continue;
        const int id = next++;
        bool border = false;
        size_t area = 0;
        stack.assign(1, int(i));
        lab[i] = id;
        while (!stack.empty()) {
          const int c = stack.back();
          stack.pop_back();
          ++area;
          const int cx = c % g.nx, cy = c / g.nx;
          if (cx == 0 || cy == 0 || cx == g.nx - 1 || cy == g.ny - 1) border = true;
          const int nb[4][2] = {{cx - 1, cy}, {cx + 1, cy}, {cx, cy - 1}, {cx, cy + 1}};
          for (const auto& n : nb) {
            if (n[0] < 0 || n[1] < 0 || n[0] >= g.nx || n[1] >= g.ny) continue;
            const size_t j = size_t(n[1]) * g.nx + n[0];
            if (lab[j] == -1 && region[j]) {
              lab[j] = id;
              stack.push_back(int(j));
            }
          }
        }
        if (border || double(area) * res * res < 2.0) continue;
        // (x, y) is the first cell of this component in bottom-up scan order.
        auto bnd = trace(lab, g.nx, g.ny, id, x, y, 8 * area + 16);
        double per = 0;
        for (size_t k = 0; k < bnd.size(); ++k) {
          const auto& p = bnd[k];
          const auto& q = bnd[(k + 1) % bnd.size()];
          per += std::hypot(p.first - q.first, p.second - q.second) * res;
        }
        cands.push_back({D, std::move(bnd), per, R});
      }
  }
  if (cands.empty())
    throw std::runtime_error("auto-loop: no free space with clearance >= " + std::to_string(dmin) +
                             " m in plan " + plan.source);
  double best_per = 0;
  for (const auto& c : cands) best_per = std::max(best_per, c.perimeter);
  // Order: larger D first among candidates whose loop is at least 85 % of the longest; then the rest by length.
  std::stable_sort(cands.begin(), cands.end(), [&](const Candidate& a, const Candidate& c) {
    const bool ga = a.perimeter >= 0.85 * best_per, gc = c.perimeter >= 0.85 * best_per;
    if (ga != gc) return ga;
    if (ga && a.D != c.D) return a.D > c.D;
    if (ga && a.R != c.R) return a.R > c.R;  // the opened (smoother) region first
    return a.perimeter > c.perimeter;
  });
  std::string tried;
  for (const auto& c : cands) {
    // Cell centres -> smoothed (moving average over ~1 m) -> control points every ~0.5 m.
    const size_t n = c.boundary.size();
    std::vector<V> pts(n);
    for (size_t k = 0; k < n; ++k) pts[k] = g.center(c.boundary[k].first, c.boundary[k].second);
    const int half = std::min(int(n / 4), std::max(1, int(1.0 / res)));
    std::vector<V> sm = pts;
    // Moving-average passes until the B-spline's tightest turn has a radius >= kMinRadius (or 10 passes).
    for (int pass = 1; pass <= 10; ++pass) {
      std::vector<V> nxt(n, V::Zero());
      V acc = V::Zero();
      for (int j = -half; j <= half; ++j) acc += sm[size_t((j % int(n) + int(n)) % int(n))];
      for (size_t k = 0; k < n; ++k) {
        nxt[k] = acc / double(2 * half + 1);
        acc += sm[(k + size_t(half) + 1) % n];
        acc -= sm[(k + n - size_t(half)) % n];
      }
      sm.swap(nxt);
      if (pass < 2) continue;
      std::vector<V> ctrl;
      double run = 1e9;
      for (size_t k = 0; k < n; ++k) {
        if (k > 0) run += (sm[k] - sm[k - 1]).norm();
        if (run >= 0.5) {
          ctrl.push_back(sm[k]);
          run = 0;
        }
      }
      if (ctrl.size() >= 2 && (ctrl.back() - ctrl.front()).norm() < 0.25) ctrl.pop_back();
      if (ctrl.size() < 4) break;
      const Motion m(ctrl, true, SpeedSpec{0.5, 0.4}, 0, 0);
      const auto path = m.sample_path(0.02);
      double kmax = 0;
      for (size_t i = 2; i < path.size(); ++i) {
        const V a = path[i - 1] - path[i - 2], b = path[i] - path[i - 1];
        if (a.norm() < 1e-4 || b.norm() < 1e-4) continue;
        const double ang = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
        kmax = std::max(kmax, ang / (0.5 * (a.norm() + b.norm())));
      }
      if (kmax > 1.0 / kMinRadius) {
        if (pass < 10) continue;
        tried += " D=" + std::to_string(c.D) + " too tight (radius " + std::to_string(1.0 / kmax) + " m);";
        break;
      }
      const double clr = min_clearance(plan, path);
      std::ostringstream os;
      os << " D=" << c.D << " passes=" << pass << " len=" << m.length() << " clearance=" << clr
         << " min_radius=" << 1.0 / std::max(kmax, 1e-9) << ";";
      tried += os.str();
      if (clr < cfg.clearance_m) break;
      AutoLoopResult r;
      r.control = std::move(ctrl);
      r.offset_m = c.D;
      r.min_clearance_m = clr;
      r.length_m = m.length();
      r.info = "auto-loop:" + os.str() + " grid " + std::to_string(res) + " m" +
               (bounded ? " (no enclosed free space: loop inside the plan's bounding box)" : "");
      return r;
    }
  }
  throw std::runtime_error("auto-loop: no candidate loop keeps " + std::to_string(cfg.clearance_m) +
                           " m from the walls in plan " + plan.source + " (tried:" + tried + ")");
}

}  // namespace fploc::sim
