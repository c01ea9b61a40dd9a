#include "fploc/plandiff/plan_diff.h"

#include "fploc/core/segment2d.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fploc::plandiff {
namespace {

using V2 = Eigen::Vector2d;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool blocks(const Element& e, const V2& p, const V2& q) {
  if (e.kind == ElementKind::kSegment) return segments_cross(p, q, e.a, e.b);
  const V2 d = q - p;
  const double t = std::clamp((e.c - p).dot(d) / std::max(d.squaredNorm(), 1e-12), 0.0, 1.0);
  if ((p + t * d - e.c).norm() >= e.r) return false;
  if (e.kind == ElementKind::kCircle) return true;
  // Arc: the first crossing of the full circle must lie on the arc.
  const double b = d.dot(p - e.c), c = (p - e.c).squaredNorm() - e.r * e.r, a = d.squaredNorm();
  const double disc = b * b - a * c;
  if (disc < 0) return false;
  for (double s : {(-b - std::sqrt(disc)) / a, (-b + std::sqrt(disc)) / a}) {
    if (s <= 0 || s >= 1) continue;
    const V2 h = p + s * d - e.c;
    double ang = std::atan2(h.y(), h.x());
    while (ang < e.a0) ang += 2 * M_PI;
    if (ang <= e.a1) return true;
  }
  return false;
}

template <class T>
double median_of(std::vector<T> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + long(m), v.end());
  return double(v[m]);
}

// The median of the cluster of offsets farthest from the sensor that holds at least min_share of them (and >= 3):
// side = +1 when the sensor is on the side the offsets grow towards (-1 the other). Clusters split at gaps > gap.
// What stands in front of a wall (shelves, furniture along it) is nearer the sensor, never behind the wall.
double far_median(std::vector<float> v, double side, double gap, double min_share) {
  if (v.empty()) return 0;
  if (gap <= 0) return median_of(std::move(v));
  for (float& x : v) x = float(side * x);  // ascending = farthest first
  std::sort(v.begin(), v.end());
  const size_t need = std::max<size_t>(3, size_t(std::ceil(min_share * double(v.size()))));
  for (size_t i = 0; i < v.size();) {
    size_t j = i + 1;
    while (j < v.size() && v[j] - v[j - 1] <= gap) ++j;
    if (j - i >= need) return side * double(v[i + (j - i) / 2]);
    i = j;
  }
  return side * median_of(std::move(v));
}

V2 left_normal(const Element& e) {
  const V2 d = (e.b - e.a).normalized();
  return V2(-d.y(), d.x());
}

int64_t cell_key(int ix, int iy) { return (int64_t(ix) << 32) ^ int64_t(uint32_t(iy)); }

}  // namespace

const char* status_name(Status s) {
  switch (s) {
    case Status::kUnobserved: return "unobserved";
    case Status::kSeen: return "seen";
    case Status::kMissing: return "missing";
    case Status::kMoved: return "moved";
  }
  return "?";
}

const char* height_name(Height h) {
  switch (h) {
    case Height::kUnknown: return "unknown";
    case Height::kTall: return "tall";
    case Height::kLow: return "low";
  }
  return "?";
}

int Diff::count(Status s) const {
  return int(std::count_if(elements.begin(), elements.end(), [s](const ElementDiff& e) { return e.status == s; }));
}

PlanDiff::PlanDiff(FloorPlan plan, Options o)
    : plan_(std::move(plan)), o_(o), scale_(plan_.elements.size()), refine_(plan_.elements.size()) {
  if (plan_.elements.empty()) throw std::runtime_error("plan diff: the plan has no elements");
  acc_.resize(plan_.elements.size());
  for (size_t i = 0; i < plan_.elements.size(); ++i) {
    const Element& e = plan_.elements[i];
    if (e.kind == ElementKind::kSegment) {
      const double len = (e.b - e.a).norm();
      if (len < 1e-6) continue;
      const int n = std::max(1, int(std::floor(len / o_.probe_step_m)));
      for (int k = 0; k < n; ++k) {
        const double t = (k + 0.5) / n;
        probes_.push_back({e.a + t * (e.b - e.a), left_normal(e), int(i)});
      }
    } else {
      const double a0 = e.kind == ElementKind::kArc ? e.a0 : 0.0, a1 = e.kind == ElementKind::kArc ? e.a1 : 2 * M_PI;
      const int n = std::max(4, int(std::ceil(e.r * (a1 - a0) / o_.probe_step_m)));
      for (int k = 0; k < n; ++k) {
        const double a = a0 + (k + 0.5) * (a1 - a0) / n;
        const V2 u(std::cos(a), std::sin(a));
        probes_.push_back({e.c + e.r * u, u, int(i)});
      }
    }
  }
  probe_expected_.assign(probes_.size(), 0);
  probe_seen_.assign(probes_.size(), 0);
  probe_through_.assign(probes_.size(), 0);
  const Box2 bb = plan_.bounds();
  gmin_ = bb.min - V2(1, 1);
  gx_ = int(std::ceil((bb.max.x() - gmin_.x() + 1) / gcell_)) + 1;
  gy_ = int(std::ceil((bb.max.y() - gmin_.y() + 1) / gcell_)) + 1;
  grid_.assign(size_t(gx_) * size_t(gy_), {});
  std::vector<int> cs;
  for (size_t i = 0; i < plan_.elements.size(); ++i) {
    const Box2 b = bounds(plan_.elements[i]);
    cells_of(b.min - V2(o_.assoc_m, o_.assoc_m), b.max + V2(o_.assoc_m, o_.assoc_m), cs);
    for (int c : cs) grid_[size_t(c)].push_back(int(i));
  }
}

void PlanDiff::cells_of(const V2& lo, const V2& hi, std::vector<int>& out) const {
  out.clear();
  const int x0 = std::clamp(int(std::floor((lo.x() - gmin_.x()) / gcell_)), 0, gx_ - 1);
  const int x1 = std::clamp(int(std::floor((hi.x() - gmin_.x()) / gcell_)), 0, gx_ - 1);
  const int y0 = std::clamp(int(std::floor((lo.y() - gmin_.y()) / gcell_)), 0, gy_ - 1);
  const int y1 = std::clamp(int(std::floor((hi.y() - gmin_.y()) / gcell_)), 0, gy_ - 1);
  for (int x = x0; x <= x1; ++x)
    for (int y = y0; y <= y1; ++y) out.push_back(x * gy_ + y);
}

bool PlanDiff::along(const Element& e, const V2& p, const V2& dir) const {
  const double smax = std::sin(o_.assoc_max_angle_deg * M_PI / 180);
  if (e.kind == ElementKind::kSegment) {
    const V2 d = e.b - e.a;
    const double len = d.norm();
    // A piece shorter than the neighbourhood the direction is taken over (a jamb, a wall's stub) is not judged:
    // its points' neighbours are mostly the walls it joins.
    return len < 2 * o_.dir_radius_m || std::abs(cross2(d / len, dir)) <= smax;
  }
  const V2 r = p - e.c;  // a circle's tangent at p is perpendicular to the radius
  const double rn = r.norm();
  return rn < 1e-9 || std::abs(r.dot(dir)) / rn <= smax;
}

int PlanDiff::nearest(const V2& p, double* signed_offset, bool* inside, const V2* sensor, const V2* dir) const {
  const int cx = int(std::floor((p.x() - gmin_.x()) / gcell_)), cy = int(std::floor((p.y() - gmin_.y()) / gcell_));
  if (cx < 0 || cy < 0 || cx >= gx_ || cy >= gy_) return -1;
  // Candidates within assoc_m, nearest first; the first whose nearest point the sensor can see (a wall
  // drawn with two lines: the far face is hidden by the near one) wins.
  static thread_local std::vector<std::pair<double, int>> cand;
  cand.clear();
  for (int i : grid_[size_t(cx * gy_ + cy)]) {
    const double d = distance(plan_.elements[size_t(i)], p);
    if (d < o_.assoc_m && (!dir || along(plan_.elements[size_t(i)], p, *dir))) cand.push_back({d, i});
  }
  if (cand.empty()) return -1;
  std::sort(cand.begin(), cand.end());
  int best = cand[0].second;
  if (cand.size() > 1 && sensor) {
    for (const auto& [d, i] : cand) {
      const V2 q = closest_point(plan_.elements[size_t(i)], p).point;
      const V2 v = *sensor - q;
      if (v.norm() < 1e-6 || !plan_blocks(*sensor, q + 0.02 * v.normalized(), i)) {
        best = i;
        break;
      }
    }
  }
  const Element& e = plan_.elements[size_t(best)];
  if (e.kind == ElementKind::kSegment) {
    const V2 d = e.b - e.a;
    const double t = (p - e.a).dot(d) / d.squaredNorm();
    *inside = t > 0.02 && t < 0.98;
    *signed_offset = left_normal(e).dot(p - e.a);
  } else {
    *inside = true;
    *signed_offset = (p - e.c).norm() - e.r;
  }
  return best;
}

bool PlanDiff::extends_beyond_end(const V2& p) const {
  const int cx = int(std::floor((p.x() - gmin_.x()) / gcell_)), cy = int(std::floor((p.y() - gmin_.y()) / gcell_));
  if (cx < 0 || cy < 0 || cx >= gx_ || cy >= gy_) return false;
  const auto& cands = grid_[size_t(cx * gy_ + cy)];
  for (int e : cands) {
    const Element& el = plan_.elements[size_t(e)];
    if (el.kind != ElementKind::kSegment) continue;
    const V2 d = el.b - el.a;
    const double len = d.norm();
    if (len < 1e-6 || std::abs(left_normal(el).dot(p - el.a)) >= o_.ext_lateral_m) continue;
    const double t = (p - el.a).dot(d) / len;  // along the segment [m]
    if (t > -o_.ext_min_beyond_m && t < len + o_.ext_min_beyond_m) continue;
    // On the segment's line past its end, and on no other element (the wall meeting it at a corner, a jamb).
    bool clear = true;
    for (int i : cands)
      if (i != e && distance(plan_.elements[size_t(i)], p) < o_.ext_clear_m) {
        clear = false;
        break;
      }
    if (clear) return true;
  }
  return false;
}

int PlanDiff::extended_element(const V2& a, const V2& b) const {
  const V2 u = (b - a).normalized();
  int best = -1;
  double best_d = o_.ext_touch_m;
  for (size_t i = 0; i < plan_.elements.size(); ++i) {
    const Element& e = plan_.elements[i];
    if (e.kind != ElementKind::kSegment) continue;
    const double len = (e.b - e.a).norm();
    if (len < 0.3) continue;
    const V2 v = (e.b - e.a) / len;
    if (std::abs(cross2(u, v)) > 0.09) continue;  // ~5 deg
    const V2 n(-v.y(), v.x());
    if (std::abs(n.dot(a - e.a)) > o_.ext_lateral_m || std::abs(n.dot(b - e.a)) > o_.ext_lateral_m) continue;
    // The run lies past one end (overlapping the segment by at most ext_touch_m) and starts near it.
    double s0 = v.dot(a - e.a), s1 = v.dot(b - e.a);
    if (s0 > s1) std::swap(s0, s1);
    double gap = kInf;
    if (s0 >= len - o_.ext_touch_m) gap = std::abs(s0 - len);
    else if (s1 <= o_.ext_touch_m) gap = std::abs(s1);
    if (gap < best_d) best_d = gap, best = int(i);
  }
  return best;
}

bool PlanDiff::stretch_blocked(const V2& s, const Probe& pr) const {
  // The probe's own point, and for a segment both ends of the stretch it stands for (half a probe step each way,
  // within the element): a look at a wall through a slit narrower than that (two doors and a pillar's side in
  // line, 8 m away) sees a sliver that leaves few or no features, so it is no look at the wall.
  auto blocked = [&](const V2& q) {
    const V2 d = q - s;
    const double r = d.norm();
    return r > 1e-6 && plan_blocks(s, q - 0.03 * d / r, pr.element);
  };
  if (blocked(pr.p)) return true;
  const Element& el = plan_.elements[size_t(pr.element)];
  if (el.kind != ElementKind::kSegment) return false;
  const V2 ab = el.b - el.a;
  const double len = ab.norm();
  if (len < 1e-6) return false;
  const V2 u = ab / len;
  const double t = (pr.p - el.a).dot(u), h = 0.5 * o_.probe_step_m;
  return blocked(el.a + std::max(0.0, t - h) * u) || blocked(el.a + std::min(len, t + h) * u);
}

bool PlanDiff::plan_blocks(const V2& o, const V2& q, int skip) const {
  // Elements in the grid cells the ray passes (sampled at half a cell, with the neighbours).
  const double len = (q - o).norm();
  const int n = std::max(1, int(std::ceil(len / (0.5 * gcell_))));
  static thread_local std::vector<int> seen;
  seen.clear();
  for (int k = 0; k <= n; ++k) {
    const V2 p = o + (q - o) * (double(k) / n);
    const int cx = int(std::floor((p.x() - gmin_.x()) / gcell_)), cy = int(std::floor((p.y() - gmin_.y()) / gcell_));
    if (cx < 0 || cy < 0 || cx >= gx_ || cy >= gy_) continue;
    for (int i : grid_[size_t(cx * gy_ + cy)]) {
      if (i == skip || std::find(seen.begin(), seen.end(), i) != seen.end()) continue;
      seen.push_back(i);
      if (blocks(plan_.elements[size_t(i)], o, q)) return true;
    }
  }
  return false;
}

void PlanDiff::add_frame(double x, double y, double yaw, const std::vector<Eigen::Vector2f>& points,
                         const Eigen::Matrix3d* pose_cov, bool pose_ok, const Heights* heights) {
  // A pose that is not finite is no registered scan (its points all fell into one "new" cell at INT_MIN).
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(yaw)) return;
  const int frame = frames_++;
  // Change evidence only from a pose the localizer calls good (status OK, small covariance); the scale takes all.
  bool evidence = pose_ok;
  if (evidence && pose_cov) {
    const Eigen::Matrix2d pc = pose_cov->topLeftCorner<2, 2>();
    const double tr = pc.trace(), det = pc.determinant();
    const double lmax = 0.5 * tr + std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
    if (!pose_cov->allFinite() ||
        (o_.max_pose_sigma_m > 0 && lmax > o_.max_pose_sigma_m * o_.max_pose_sigma_m) ||
        (o_.max_pose_yaw_sigma_deg > 0 && (*pose_cov)(2, 2) > std::pow(o_.max_pose_yaw_sigma_deg * M_PI / 180, 2)))
      evidence = false;
  }
  if (evidence) ++evidence_frames_;
  const V2 s(x, y);
  const double c = std::cos(yaw), sn = std::sin(yaw);
  const int nb = int(std::lround(360.0 / o_.bin_deg));
  const double bin_w = 2 * M_PI / nb;
  auto bin_of = [&](const V2& d) {
    int b = int(std::floor((std::atan2(d.y(), d.x()) + M_PI) / bin_w));
    return ((b % nb) + nb) % nb;
  };
  // Heights: the highest 3D wall point of this scan in each new-structure cell (above the floor), and how high the
  // scan's beams reach: the steepest upward elevation of any of its wall points (a wall's top ring).
  std::unordered_map<int64_t, float> top_here;
  double tan_up = -kInf;
  const bool use_heights = heights && evidence && o_.new_min_height_m > 0 && !heights->points.empty();
  if (use_heights) {
    ++height_frames_;
    for (const auto& q : heights->points) {
      const double rxy = std::hypot(double(q.x()), double(q.y()));
      if (!(rxy >= o_.min_range_m && rxy <= o_.max_range_m) || !std::isfinite(q.z())) continue;
      tan_up = std::max(tan_up, double(q.z()) / rxy);
      const V2 w = s + V2(c * q.x() - sn * q.y(), sn * q.x() + c * q.y());
      const float h = float(heights->sensor_z + q.z());
      float& t = top_here.try_emplace(cell_key(int(std::floor(w.x() / o_.new_cell_m)), int(std::floor(w.y() / o_.new_cell_m))),
                                      -1.0f).first->second;
      t = std::max(t, h);
    }
  }
  // The highest point of this scan within a cell of the new-structure cell (ix, iy) (-1: none).
  auto top_near = [&](int ix, int iy) {
    float t = -1;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy) {
        const auto it = top_here.find(cell_key(ix + dx, iy + dy));
        if (it != top_here.end()) t = std::max(t, it->second);
      }
    return t;
  };
  struct Obs {
    float range;
    int element;
  };
  std::vector<std::vector<Obs>> bins(static_cast<size_t>(nb));
  std::vector<float> min_range(size_t(nb), std::numeric_limits<float>::infinity());
  std::vector<std::vector<float>> offs(plan_.elements.size());
  // The offsets of the points that lie on straight structure along their element (a known direction): the far cluster
  // is taken among these (a window's reveal or a jamb seen past a wall's face is no straight run along it).
  std::vector<std::vector<float>> flat_offs(plan_.elements.size());
  std::vector<std::vector<float>> flat_half_offs[2] = {std::vector<std::vector<float>>(plan_.elements.size()),
                                                       std::vector<std::vector<float>>(plan_.elements.size())};
  std::vector<std::vector<float>> half_offs[2] = {std::vector<std::vector<float>>(plan_.elements.size()),
                                                  std::vector<std::vector<float>>(plan_.elements.size())};
  std::vector<V2> along_sum(plan_.elements.size(), V2::Zero());  // sum of (point - sensor) of the inside points
  // The scan's points in range, on the plan, and the direction of the straight structure each lies on (its
  // neighbours' principal axis, where they are straight enough to tell).
  std::vector<V2> wp;
  std::vector<double> wr;
  wp.reserve(points.size());
  wr.reserve(points.size());
  for (const auto& pf : points) {
    const V2 ps(pf.x(), pf.y());
    const double r = ps.norm();
    if (!(r >= o_.min_range_m && r <= o_.max_range_m)) continue;
    wp.push_back(s + V2(c * ps.x() - sn * ps.y(), sn * ps.x() + c * ps.y()));
    wr.push_back(r);
  }
  std::vector<V2> pdir(wp.size(), V2::Zero());
  if (o_.assoc_max_angle_deg > 0 && o_.dir_radius_m > 0) {
    const double cs = o_.dir_radius_m, r2 = cs * cs;
    std::unordered_map<int64_t, std::vector<int>> pg;
    auto key = [&](const V2& q) { return cell_key(int(std::floor(q.x() / cs)), int(std::floor(q.y() / cs))); };
    for (size_t i = 0; i < wp.size(); ++i) pg[key(wp[i])].push_back(int(i));
    std::vector<int> nb_idx;
    for (size_t i = 0; i < wp.size(); ++i) {
      const int ix = int(std::floor(wp[i].x() / cs)), iy = int(std::floor(wp[i].y() / cs));
      nb_idx.clear();
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy) {
          const auto it = pg.find(cell_key(ix + dx, iy + dy));
          if (it == pg.end()) continue;
          for (int j : it->second)
            if ((wp[size_t(j)] - wp[i]).squaredNorm() <= r2) nb_idx.push_back(j);
        }
      if (int(nb_idx.size()) < o_.dir_min_points) continue;
      V2 m = V2::Zero();
      for (int j : nb_idx) m += wp[size_t(j)];
      m /= double(nb_idx.size());
      Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
      for (int j : nb_idx) {
        const V2 q = wp[size_t(j)] - m;
        C += q * q.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
      const double l0 = es.eigenvalues()(0), l1 = es.eigenvalues()(1);
      if (!(l1 > 0) || l0 > o_.dir_max_flatness * l1) continue;
      pdir[i] = es.eigenvectors().col(1).normalized();
    }
  }
  for (size_t pi = 0; pi < wp.size(); ++pi) {
    const V2& p = wp[pi];
    const double r = wr[pi];
    double off = 0;
    bool inside = false;
    // The plain nearest element (for the drawing scale, as before), and the nearest the point's structure runs along.
    const int e0 = nearest(p, &off, &inside, &s);
    const double off0 = off;
    const bool inside0 = inside;
    int e = e0;
    if (e0 >= 0 && pdir[pi].squaredNorm() > 0 && !along(plan_.elements[size_t(e0)], p, pdir[pi]))
      e = nearest(p, &off, &inside, &s, &pdir[pi]);
    bool e_as_new = false;  // continues a wall beyond its drawn end: unexplained (see extends_beyond_end)
    const int b = bin_of(p - s);
    bins[size_t(b)].push_back({float(r), e});
    min_range[size_t(b)] = std::min(min_range[size_t(b)], float(r));
    if (e >= 0 && !inside && extends_beyond_end(p)) e_as_new = true;
    const bool e0_as_new = e0 == e ? e_as_new : e0 >= 0 && !inside0 && extends_beyond_end(p);
    if (e0 >= 0 && !e0_as_new) {
      const Element& el = plan_.elements[size_t(e0)];
      if (inside0 && el.kind == ElementKind::kSegment && std::abs(off0) < o_.scale_max_offset_m) {
        // Scale model: off = scale * n.(q - sensor) + n.b (b: this scan's registration bias).
        const V2 n = left_normal(el);
        const double dd = n.dot(p - s) - off0;
        scale_.add_point(e0, Eigen::Vector3d(dd, n.x(), n.y()), off0);
      }
    }
    if (!pose_ok) continue;
    if (e >= 0 && !e_as_new) {
      if (inside) {
        offs[size_t(e)].push_back(float(off));
        const bool flat = pdir[pi].squaredNorm() > 0;
        if (flat) flat_offs[size_t(e)].push_back(float(off));
        along_sum[size_t(e)] += p - s;
        const Element& es = plan_.elements[size_t(e)];
        if (es.kind == ElementKind::kSegment) {
          const V2 d = es.b - es.a;
          const double t = d.squaredNorm() > 0 ? (p - es.a).dot(d) / d.squaredNorm() : 0.0;
          half_offs[t < 0.5 ? 0 : 1][size_t(e)].push_back(float(off));
          if (flat) flat_half_offs[t < 0.5 ? 0 : 1][size_t(e)].push_back(float(off));
        }
      }
    } else if (evidence) {
      const int ix = int(std::floor(p.x() / o_.new_cell_m)), iy = int(std::floor(p.y() / o_.new_cell_m));
      Cell& cell = cells_[cell_key(ix, iy)];
      if (cell.last_frame != frame) {
        cell.last_frame = frame;
        ++cell.frames;
        if (cell.hit_frames.size() < kMaxHitFrames) cell.hit_frames.push_back(frame);
        if (use_heights) {
          const float t = top_near(ix, iy);
          cell.top_m = std::max(cell.top_m, t);
          if (t >= o_.new_min_height_m) ++cell.tall_frames;
          // Could this scan tell whether the structure there rises above new_min_height_m: its highest beam at this
          // range passes above it, or the structure's top was seen (its points end well below the highest beam: the
          // beams above it passed over; margin for the rings' spacing)?
          if (std::isfinite(tan_up)) {
            const double reach = heights->sensor_z + r * tan_up;
            if (reach >= o_.new_min_height_m + 0.1 || (t >= 0 && t < reach - (0.15 + 0.05 * r))) ++cell.checkable_frames;
          }
        }
      }
      ++cell.points;
      Cell& vc = view_[cell_key(int(std::floor(p.x() / o_.new_view_cell_m)), int(std::floor(p.y() / o_.new_view_cell_m)))];
      if (vc.last_frame != frame) {
        vc.last_frame = frame;
        ++vc.frames;
      }
    }
  }
  const bool cov_given = pose_cov && pose_cov->allFinite() && (*pose_cov)(0, 0) >= 0 && (*pose_cov)(1, 1) >= 0 &&
                         (*pose_cov)(2, 2) >= 0;
  for (size_t e = 0; e < offs.size(); ++e) {
    if (offs[e].size() < 5) continue;
    // The pose's variance along the element's normal at its points: the pose error (dx, dy, dyaw) moves them along
    // n by n . (dx, dy) + dyaw n . perp(rc) (rc: the mean point relative to the sensor, perp: +90 deg).
    double v = -1;
    if (cov_given) {
      const Element& el = plan_.elements[e];
      const V2 rc = along_sum[e] / double(offs[e].size());
      V2 n = V2::Zero();
      if (el.kind == ElementKind::kSegment) {
        n = left_normal(el);
      } else if ((s + rc - el.c).norm() > 1e-9) {
        n = (s + rc - el.c).normalized();
      }
      if (n.squaredNorm() > 0) {
        const Eigen::Vector3d cv(n.x(), n.y(), n.y() * rc.x() - n.x() * rc.y());
        v = cv.dot(*pose_cov * cv);
      }
    }
    // A scan whose pose is loose (along a corridor, say) still measures the offsets of the elements its
    // uncertainty runs along: those are kept when the variance along their normal is within the limit.
    if (!evidence && !(v >= 0 && (o_.max_pose_sigma_m <= 0 || v <= o_.max_pose_sigma_m * o_.max_pose_sigma_m)))
      continue;
    // The sensor's side of the element: its points' offsets grow towards it (+1) or away (-1).
    double side = 1;
    {
      const Element& el = plan_.elements[e];
      if (el.kind == ElementKind::kSegment) side = left_normal(el).dot(s - el.a) >= 0 ? 1 : -1;
      else side = (s - el.c).norm() >= el.r ? 1 : -1;
    }
    // The far cluster among the points on straight structure along the element when there are enough of them,
    // else the plain median of all.
    auto frame_offset = [&](const std::vector<float>& all, const std::vector<float>& flat, size_t min_n) {
      if (flat.size() >= min_n) return far_median(flat, side, o_.offset_cluster_gap_m, o_.offset_cluster_share);
      return median_of(all);
    };
    acc_[e].frame_offsets.push_back(float(frame_offset(offs[e], flat_offs[e], 5)));
    for (int h = 0; h < 2; ++h)
      if (half_offs[h][e].size() >= 3)
        acc_[e].half_offsets[h].push_back(float(frame_offset(half_offs[h][e], flat_half_offs[h][e], 3)));
    if (!o_.moved_pose_covariance || !(v >= 0)) continue;
    acc_[e].pose_var += v;
    ++acc_[e].pose_frames;
  }
  // As-built refinement (wall_refinement.h): each well-seen wall's median offset in this scan, where along it,
  // and how the scan's registration error moves its points along its normal.
  std::vector<WallRefinement::Observation> obs;
  for (size_t e = 0; e < offs.size() && evidence; ++e) {
    const Element& el = plan_.elements[e];
    if (el.kind != ElementKind::kSegment || int(offs[e].size()) < o_.refine_min_points) continue;
    const V2 d = el.b - el.a;
    const V2 rc = along_sum[e] / double(offs[e].size());  // mean point, relative to the sensor
    const double t = std::clamp((s + rc - el.a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    const V2 n = left_normal(el);
    obs.push_back({int(e), t, median_of(offs[e]), Eigen::Vector3d(-n.x(), -n.y(), -(n.y() * rc.x() - n.x() * rc.y()))});
  }
  refine_.add_scan(obs);
  scale_.end_scan();
  if (!evidence) return;  // the rest is change evidence
  // Every unexplained cell seen so far: was it in view in this scan (in range, nothing measured in front)?
  // Static structure is hit in a good share of the scans that see its place; a person's track is not.
  for (auto& [k, cell] : view_) {
    const int ix = int(k >> 32), iy = int(int32_t(uint32_t(k & 0xffffffff)));
    const V2 d = V2((ix + 0.5) * o_.new_view_cell_m, (iy + 0.5) * o_.new_view_cell_m) - s;
    const double r = d.norm();
    if (cell.last_frame == frame) {
      ++cell.in_view;
      continue;
    }
    if (r < o_.min_range_m || r > o_.max_range_m) continue;
    if (min_range[size_t(bin_of(d))] < r - 0.2) continue;
    ++cell.in_view;
  }

  // Visibility probes: expected (in range, not grazing, not behind another plan element, nothing measured
  // well in front of it) and seen (a point of this element in the probe's bearing).
  const double sin_inc = std::sin(o_.min_incidence_deg * M_PI / 180);
  std::vector<int> expected(plan_.elements.size(), 0);
  for (size_t pi = 0; pi < probes_.size(); ++pi) {
    const Probe& pr = probes_[pi];
    const V2 d = pr.p - s;
    const double r = d.norm();
    if (r < o_.min_range_m + 0.2 || r > o_.max_range_m - 0.5) continue;
    const double inc = std::abs(pr.n.dot(d)) / r;
    if (inc < sin_inc) continue;
    const Element& el = plan_.elements[size_t(pr.element)];
    if (el.kind != ElementKind::kSegment && pr.n.dot(d) > 0) continue;  // far side of a pillar
    const int b = bin_of(d);
    bool seen = false;
    for (int db = -1; db <= 1 && !seen; ++db)
      for (const Obs& ob : bins[size_t(((b + db) % nb + nb) % nb)])
        if (ob.element == pr.element && std::abs(ob.range - r) < o_.assoc_m + 0.1) {
          seen = true;
          break;
        }
    if (!seen) {
      // Something unmapped in front (new structure observed in this scan): in the probe's bearing bin or either
      // neighbour, as `seen` looks (a sparse scan's points on a new partition fell in the neighbours only, and the
      // wall behind it counted as expected but unseen: "missing").
      bool hidden = false;
      for (int db = -1; db <= 1 && !hidden; ++db)
        hidden = min_range[size_t(((b + db) % nb + nb) % nb)] < r - o_.occlusion_margin_m;
      if (hidden) continue;
    }
    if (stretch_blocked(s, pr)) continue;  // another plan element in front of (part of) the probe's stretch
    Acc& a = acc_[size_t(pr.element)];
    ++a.expected;
    ++expected[size_t(pr.element)];
    if (seen) ++a.seen;
    ++probe_expected_[pi];
    if (seen) {
      ++probe_seen_[pi];
    } else {
      // Seen through: something measured beyond the probe in its bearing (the wall is not there).
      for (const Obs& ob : bins[size_t(b)])
        if (ob.range > r + o_.part_through_m) {
          ++probe_through_[pi];
          break;
        }
    }
  }
  for (size_t e = 0; e < expected.size(); ++e)
    if (expected[e] > 0) ++acc_[e].frames_expected;
}

// The uncertainty of an element's offset (the median of its scans' median offsets): the scans' robust spread
// over at most moved_max_looks independent looks (consecutive scans see the same), plus the localizer's own
// error along the normal (moved_pose_sigma_m), which does not average out over scans.
// With the localizer's covariance, its mean variance along the normal over the element's scans, if larger.
double PlanDiff::offset_sigma(const ElementDiff& e) const {
  const double n = std::min(double(e.frames_with_points), o_.moved_max_looks);
  const double ss = 1.4826 * e.offset_spread_m;
  const double pose2 = std::max(o_.moved_pose_sigma_m * o_.moved_pose_sigma_m, e.pose_sigma_m * e.pose_sigma_m);
  return std::sqrt(pose2 + (n > 0 ? ss * ss / n : ss * ss));
}

// Both halves of a segment measured and each offset by as much as the whole must be (moved_both_halves).
bool PlanDiff::halves_moved(const ElementDiff& e) const {
  if (!o_.moved_both_halves) return true;
  for (int h = 0; h < 2; ++h)
    if (e.half_frames[h] < o_.min_frames || e.half_offset_m[h] * e.offset_m <= 0 ||
        std::abs(e.half_offset_m[h]) - o_.moved_z * e.offset_sigma_m < o_.moved_min_m)
      return false;
  return true;
}

Diff PlanDiff::result() const {
  Diff d;
  d.frames = frames_;
  d.evidence_frames = evidence_frames_;
  d.height_frames = height_frames_;
  d.refined = refine_.result({o_.refine_obs_sigma_m, o_.refine_prior_m, o_.refine_min_info, o_.refine_ends, o_.min_frames});
  const DrawingScale::Estimate scale = scale_.estimate(frames_, o_.min_frames);
  d.scale_error = scale.error;
  d.scale_sigma = scale.sigma;
  d.scale_points = scale.points;
  d.elements.resize(plan_.elements.size());
  for (size_t i = 0; i < plan_.elements.size(); ++i) {
    const Acc& a = acc_[i];
    ElementDiff& e = d.elements[i];
    e.id = int(i);
    e.frames_with_points = int(a.frame_offsets.size());
    e.frames_expected = a.frames_expected;
    e.probes_expected = a.expected;
    e.probes_seen = a.seen;
    if (!a.frame_offsets.empty()) {
      e.offset_m = median_of(a.frame_offsets);
      std::vector<float> dev;
      for (float v : a.frame_offsets) dev.push_back(std::abs(v - float(e.offset_m)));
      e.offset_spread_m = median_of(dev);
      if (a.pose_frames > 0) e.pose_sigma_m = std::sqrt(a.pose_var / a.pose_frames);
      e.offset_sigma_m = offset_sigma(e);
      for (int h = 0; h < 2; ++h) {
        e.half_frames[h] = int(a.half_offsets[h].size());
        if (e.half_frames[h] > 0) e.half_offset_m[h] = median_of(a.half_offsets[h]);
      }
    }
    if (a.frames_expected >= o_.min_frames && a.expected >= o_.missing_min_expected &&
        e.seen_ratio() < o_.missing_seen_ratio)
      e.status = Status::kMissing;
    else if (e.frames_with_points >= o_.min_frames && std::abs(e.offset_m) >= o_.moved_min_m &&
             std::abs(e.offset_m) - o_.moved_z * e.offset_sigma_m >= o_.moved_min_m &&
             e.offset_spread_m <= o_.moved_max_spread_m &&
             (plan_.elements[i].kind != ElementKind::kSegment ||
              ((plan_.elements[i].b - plan_.elements[i].a).norm() >= o_.moved_min_length_m && halves_moved(e))))
      e.status = Status::kMoved;
    else if (e.frames_with_points > 0 || a.seen > 0)
      e.status = Status::kSeen;
  }

  // Missing parts of elements otherwise seen: runs of probes expected, not seen, and seen through.
  for (size_t k = 0; k < probes_.size();) {
    const int el = probes_[k].element;
    size_t end = k;
    while (end < probes_.size() && probes_[end].element == el) ++end;
    const Element& pe = plan_.elements[size_t(el)];
    if (pe.kind == ElementKind::kSegment && d.elements[size_t(el)].status == Status::kSeen) {
      // Of the expected observations that measured something at or beyond the probe (a sparse scan often
      // has no point in a probe's bearing at all), most saw through it.
      auto gone = [&](size_t i) {
        const int told = probe_seen_[i] + probe_through_[i];
        return probe_expected_[i] >= o_.part_min_expected && probe_through_[i] >= o_.part_min_through &&
               probe_seen_[i] < o_.part_seen_ratio * told;
      };
      const double n = double(end - k);
      for (size_t i = k; i < end;) {
        if (!gone(i)) {
          ++i;
          continue;
        }
        MissingPart mp;
        mp.element = el;
        size_t j = i;
        for (; j < end && gone(j); ++j) {
          mp.expected += probe_expected_[j];
          mp.seen += probe_seen_[j];
          mp.through += probe_through_[j];
        }
        // Probe q sits at (q + 0.5) / n of the segment: the piece spans its probes' cells, and half the cell
        // of a neighbour that was seen through about as often as seen (the piece's end lies in that cell).
        auto half = [&](size_t q) {
          const int told = probe_seen_[q] + probe_through_[q];
          return probe_through_[q] >= o_.part_min_through && probe_seen_[q] < 2 * o_.part_seen_ratio * told ? 0.5 : 0.0;
        };
        const double t0 = double(i - k) - (i > k ? half(i - 1) : 0.0), t1 = double(j - k) + (j < end ? half(j) : 0.0);
        mp.a = pe.a + (t0 / n) * (pe.b - pe.a);
        mp.b = pe.a + (t1 / n) * (pe.b - pe.a);
        d.missing_parts.push_back(mp);
        i = j;
      }
    }
    k = end;
  }
  // Elements whose missing parts cover most of their length are missing (what was seen there stands elsewhere).
  if (o_.missing_part_share > 0) {
    std::vector<double> gone(plan_.elements.size(), 0.0);
    for (const auto& mp : d.missing_parts) gone[size_t(mp.element)] += mp.length();
    for (size_t i = 0; i < plan_.elements.size(); ++i) {
      const Element& pe = plan_.elements[i];
      if (pe.kind != ElementKind::kSegment || gone[i] <= 0) continue;
      if (gone[i] >= o_.missing_part_share * (pe.b - pe.a).norm()) d.elements[i].status = Status::kMissing;
    }
    d.missing_parts.erase(std::remove_if(d.missing_parts.begin(), d.missing_parts.end(), [&](const MissingPart& mp) {
                            return d.elements[size_t(mp.element)].status == Status::kMissing;
                          }), d.missing_parts.end());
  }

  // New structure: cells hit in enough frames, then straight runs by greedy RANSAC.
  std::vector<V2> pts;
  std::vector<int> pf;
  std::vector<const std::vector<int>*> ph;
  std::vector<const Cell*> pc;
  for (const auto& [k, c] : cells_) {
    if (c.frames < o_.new_min_frames) continue;
    const int ix = int(k >> 32), iy = int(int32_t(uint32_t(k & 0xffffffff)));
    {
      const V2 q((ix + 0.5) * o_.new_cell_m, (iy + 0.5) * o_.new_cell_m);
      const auto it = view_.find(cell_key(int(std::floor(q.x() / o_.new_view_cell_m)), int(std::floor(q.y() / o_.new_view_cell_m))));
      if (it == view_.end() || it->second.frames < o_.new_min_hit_ratio * it->second.in_view) continue;
    }
    pts.emplace_back((ix + 0.5) * o_.new_cell_m, (iy + 0.5) * o_.new_cell_m);
    pf.push_back(c.frames);
    ph.push_back(&c.hit_frames);
    pc.push_back(&c);
  }
  // Deterministic order (the hash map's is not).
  std::vector<size_t> order(pts.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return pts[a].x() != pts[b].x() ? pts[a].x() < pts[b].x() : pts[a].y() < pts[b].y();
  });
  std::vector<V2> P;
  std::vector<int> F;
  std::vector<const std::vector<int>*> H;
  std::vector<const Cell*> CL;
  for (size_t i : order) P.push_back(pts[i]), F.push_back(pf[i]), H.push_back(ph[i]), CL.push_back(pc[i]);
  // Was a run seen at once? Frames whose cells of the run cover, without a gap wider than new_max_gap_m, a stretch
  // >= `span` along v (new_min_span_m): >= new_min_frames of them and >= new_min_span_share of the frames that hit
  // the run. Two people pacing along one line are a gap apart, but for the moments they pass each other.
  std::unordered_map<int, std::vector<double>> hits;  // frame -> positions along v of the cells it hit
  auto seen_at_once = [&](const std::vector<std::pair<double, size_t>>& on, size_t s0, size_t k, const V2& v,
                          const V2& m, double span) -> bool {
    hits.clear();
    for (size_t j = s0; j < k; ++j) {
      const double t = v.dot(P[on[j].second] - m);
      for (int f : *H[on[j].second]) hits[f].push_back(t);
    }
    int n = 0;
    for (auto& [f, ts] : hits) {
      std::sort(ts.begin(), ts.end());
      double from = ts[0], longest = 0;
      for (size_t i = 1; i <= ts.size(); ++i) {
        if (i < ts.size() && ts[i] - ts[i - 1] <= o_.new_max_gap_m) continue;
        longest = std::max(longest, ts[i - 1] - from + o_.new_cell_m);
        if (i < ts.size()) from = ts[i];
      }
      if (longest >= span) ++n;
    }
    return n >= std::max(double(o_.new_min_frames), o_.new_min_span_share * double(hits.size()));
  };
  std::vector<char> used(P.size(), 0);
  uint64_t rs = 0x9E3779B97F4A7C15ull;
  auto rnd = [&](size_t n) {
    rs = rs * 6364136223846793005ull + 1442695040888963407ull;
    return size_t(rs >> 33) % n;
  };
  const int min_cells = std::max(6, int(0.4 * o_.new_min_length_m / o_.new_cell_m));
  const int ext_min_cells = std::max(4, int(0.4 * o_.ext_min_length_m / o_.new_cell_m));
  const int any_min_cells = std::min(min_cells, ext_min_cells);
  for (int round = 0; round < 40; ++round) {
    std::vector<size_t> free;
    for (size_t i = 0; i < P.size(); ++i)
      if (!used[i]) free.push_back(i);
    if (int(free.size()) < any_min_cells) break;
    size_t best_a = 0, best_b = 0;
    int best_n = 0;
    for (int it = 0; it < 400; ++it) {
      const size_t a = free[rnd(free.size())], b = free[rnd(free.size())];
      if ((P[a] - P[b]).norm() < 0.3) continue;
      const V2 u = (P[b] - P[a]).normalized();
      int n = 0;
      for (size_t i : free)
        if (std::abs(cross2(u, P[i] - P[a])) < o_.new_line_tol_m) ++n;
      if (n > best_n) best_n = n, best_a = a, best_b = b;
    }
    if (best_n < any_min_cells) break;
    const V2 u = (P[best_b] - P[best_a]).normalized();
    std::vector<std::pair<double, size_t>> on;
    for (size_t i : free)
      if (std::abs(cross2(u, P[i] - P[best_a])) < o_.new_line_tol_m) on.push_back({u.dot(P[i] - P[best_a]), i});
    std::sort(on.begin(), on.end());
    size_t s0 = 0;
    for (size_t k = 1; k <= on.size(); ++k) {
      if (k < on.size() && on[k].first - on[k - 1].first <= o_.new_max_gap_m) continue;
      // Run on[s0 .. k-1].
      const double len = on[k - 1].first - on[s0].first + o_.new_cell_m;
      const int n = int(k - s0);
      if ((len >= o_.new_min_length_m && n >= min_cells) || (len >= o_.ext_min_length_m && n >= ext_min_cells)) {
        V2 m = V2::Zero();
        for (size_t j = s0; j < k; ++j) m += P[on[j].second];
        m /= n;
        Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
        for (size_t j = s0; j < k; ++j) {
          const V2 q = P[on[j].second] - m;
          C += q * q.transpose();
        }
        const double tr = C.trace(), det = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0);
        const double l1 = 0.5 * tr + std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
        V2 v = std::abs(C(0, 1)) > 1e-12 ? V2(l1 - C(1, 1), C(0, 1)).normalized() : (C(0, 0) >= C(1, 1) ? V2(1, 0) : V2(0, 1));
        double lo = kInf, hi = -kInf, ss = 0;
        int fmin = std::numeric_limits<int>::max();
        for (size_t j = s0; j < k; ++j) {
          const V2 q = P[on[j].second] - m;
          lo = std::min(lo, v.dot(q));
          hi = std::max(hi, v.dot(q));
          ss += std::pow(cross2(v, q), 2);
          fmin = std::min(fmin, F[on[j].second]);
        }
        NewStructure ns;
        ns.a = m + lo * v;
        ns.b = m + hi * v;
        ns.extends = extended_element(ns.a, ns.b);
        // Shorter than new_min_length_m: only as a wall's continuation.
        if (!(len >= o_.new_min_length_m && n >= min_cells) && ns.extends < 0) {
          s0 = k;
          continue;
        }
        // Seen at once, as a wall is, not a trail swept over scan after scan. (A wall's continuation lies on the
        // wall's own line, within ext_lateral_m: no one walks there.)
        if (o_.new_min_span_m > 0 && ns.extends < 0 &&
            !seen_at_once(on, s0, k, v, m, std::min(o_.new_min_span_m, 0.8 * (hi - lo + o_.new_cell_m)))) {
          s0 = k;
          continue;
        }
        ns.cells = n;
        ns.min_frames = fmin;
        ns.rms_m = std::sqrt(ss / n);
        // How tall: the share of its cells with points above new_min_height_m (a wall, a partition), else low when
        // most of its cells were in view from where the beams reached that high (a table, a cabinet).
        if (height_frames_ > 0) {
          int tall = 0, checkable = 0;
          std::vector<float> tops;
          for (size_t j = s0; j < k; ++j) {
            const Cell& cl = *CL[on[j].second];
            if (cl.tall_frames >= o_.new_tall_min_frames) ++tall;
            if (cl.checkable_frames >= o_.new_min_frames) ++checkable;
            if (cl.top_m >= 0) tops.push_back(cl.top_m);
          }
          if (!tops.empty()) {  // the 90th percentile of its cells' highest points: one stray point is not its top
            const size_t q = std::min(tops.size() - 1, size_t(0.9 * double(tops.size())));
            std::nth_element(tops.begin(), tops.begin() + long(q), tops.end());
            ns.top_m = tops[q];
          }
          if (tall >= o_.new_tall_share * n) ns.height = Height::kTall;
          else if (checkable >= o_.new_low_checkable_share * n) ns.height = Height::kLow;
        }
        (ns.height == Height::kLow ? d.low : d.added).push_back(ns);
      }
      s0 = k;
    }
    for (auto& [t, i] : on) used[i] = 1;  // inliers of this line are done, reported or not
  }
  return d;
}

}  // namespace fploc::plandiff
