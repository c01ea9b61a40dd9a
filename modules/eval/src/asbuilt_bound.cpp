#include "fploc/eval/asbuilt_bound.h"

#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>

namespace fploc::eval {
namespace {

using V2 = Eigen::Vector2d;

// One displacement's identity. The simulator's joints: segment ends that coincide to the millimetre (modules/sim
// perturb.cpp); a pillar's centre: its element index.
std::tuple<int, long, long> joint(const V2& p) { return {0, std::lround(p.x() * 1000), std::lround(p.y() * 1000)}; }
std::tuple<int, long, long> pillar(size_t element) { return {1, long(element), 0}; }

}  // namespace

AsBuiltBound::AsBuiltBound(const FloorPlan& plan, const AsBuiltBoundOptions& o) : plan_(plan), o_(o) {
  if (!(o.vertex_sigma_m > 0) || !(o.point_sigma_m > 0))
    throw std::invalid_argument("as-built bound: vertex_sigma_m and point_sigma_m must be > 0");
  gate_ = o.gate_m > 0 ? o.gate_m : std::max(0.08, 4 * o.vertex_sigma_m);
}

int AsBuiltBound::add_scan(const Eigen::Vector3d& pose, const std::vector<V2>& points) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  Scan sc;
  sc.sensor = pose.head<2>();
  // Each point's row: d(residual)/d(pose) (3) and its share of at most two displacements (an element's two
  // vertices, or a pillar's centre), each a 2-vector; local block ids.
  struct Row {
    Eigen::Vector3d jp;
    int v[2] = {-1, -1};
    V2 dv[2] = {V2::Zero(), V2::Zero()};
  };
  std::vector<Row> rows;
  rows.reserve(points.size());
  std::map<int, int> local;  // global id -> local block
  auto vid = [&](const std::tuple<int, long, long>& k) {
    const int g = index_.try_emplace(k, int(index_.size())).first->second;
    const auto [it, fresh] = local.try_emplace(g, int(sc.disp.size()));
    if (fresh) sc.disp.push_back(g);
    return it->second;
  };
  std::vector<char> seen(plan_.elements.size(), 0);
  for (const V2& q : points) {
    if (!q.allFinite()) continue;
    const V2 p = sc.sensor + V2(c * q.x() - s * q.y(), s * q.x() + c * q.y());
    size_t best = plan_.elements.size();
    double bd = gate_;
    for (size_t i = 0; i < plan_.elements.size(); ++i) {
      const double d = distance(plan_.elements[i], p);
      if (d < bd) bd = d, best = i;
    }
    if (best == plan_.elements.size()) continue;
    const Element& e = plan_.elements[best];
    Row r;
    V2 n;
    if (e.kind == ElementKind::kSegment) {
      const V2 ab = e.b - e.a;
      const double L2 = ab.squaredNorm();
      if (!(L2 > 0)) continue;
      const double t = std::clamp((p - e.a).dot(ab) / L2, 0.0, 1.0);
      n = V2(-ab.y(), ab.x()) / std::sqrt(L2);
      // The world wall at fraction t is displaced by (1 - t) da + t db; the residual n.(p - wall) by minus its normal part.
      r.v[0] = vid(joint(e.a)), r.dv[0] = -(1 - t) * n;
      r.v[1] = vid(joint(e.b)), r.dv[1] = -t * n;
    } else {
      const V2 d = p - e.c;
      if (!(d.norm() > 0)) continue;
      n = d.normalized();
      r.v[0] = vid(pillar(best)), r.dv[0] = -n;
    }
    const V2 rel = p - sc.sensor;
    r.jp = Eigen::Vector3d(n.x(), n.y(), n.x() * -rel.y() + n.y() * rel.x());
    rows.push_back(r);
    seen[best] = 1;
  }
  const int nv = int(sc.disp.size());
  const double wp = 1.0 / (o_.point_sigma_m * o_.point_sigma_m);
  sc.hpp.setZero();
  sc.hpv = Eigen::MatrixXd::Zero(3, 2 * nv);
  sc.hvv = Eigen::MatrixXd::Zero(2 * nv, 2 * nv);
  for (const Row& r : rows) {
    sc.hpp += wp * r.jp * r.jp.transpose();
    for (int a = 0; a < 2; ++a) {
      if (r.v[a] < 0) continue;
      sc.hpv.middleCols<2>(2 * r.v[a]) += wp * r.jp * r.dv[a].transpose();
      for (int b = 0; b < 2; ++b)
        if (r.v[b] >= 0) sc.hvv.block<2, 2>(2 * r.v[a], 2 * r.v[b]) += wp * r.dv[a] * r.dv[b].transpose();
    }
  }
  sc.points = int(rows.size());
  for (size_t i = 0; i < seen.size(); ++i)
    if (seen[i]) sc.elements.push_back(int(i));
  scans_.push_back(std::move(sc));
  return int(scans_.size()) - 1;
}

ScanBound AsBuiltBound::bound(int first, int last, int at) const {
  if (first < 0 || last >= scans() || first > last || at < first || at > last)
    throw std::out_of_range("as-built bound: scans " + std::to_string(first) + ".." + std::to_string(last) + " at " +
                            std::to_string(at) + " of " + std::to_string(scans()));
  // The window's displacements, numbered in order of appearance.
  std::map<int, int> col;
  for (int k = first; k <= last; ++k)
    for (int g : scans_[size_t(k)].disp) col.try_emplace(g, int(col.size()));
  const int n = int(col.size());
  Eigen::Matrix3d hpp = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd hpv = Eigen::MatrixXd::Zero(3, 2 * n), hvv = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  const V2 ref = scans_[size_t(at)].sensor;
  ScanBound out;
  std::vector<char> seen(plan_.elements.size(), 0);
  for (int k = first; k <= last; ++k) {
    const Scan& sc = scans_[size_t(k)];
    // A point's yaw column about ref = about its sensor + n.perp(sensor - ref): jp_ref = M jp_sensor.
    const V2 d = sc.sensor - ref;
    Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
    M(2, 0) = -d.y();
    M(2, 1) = d.x();
    hpp += M * sc.hpp * M.transpose();
    const Eigen::MatrixXd mv = M * sc.hpv;
    const int m = int(sc.disp.size());
    for (int a = 0; a < m; ++a) {
      const int ca = col.at(sc.disp[size_t(a)]);
      hpv.middleCols<2>(2 * ca) += mv.middleCols<2>(2 * a);
      for (int b = 0; b < m; ++b) hvv.block<2, 2>(2 * ca, 2 * col.at(sc.disp[size_t(b)])) += sc.hvv.block<2, 2>(2 * a, 2 * b);
    }
    out.points += sc.points;
    for (int e : sc.elements) seen[size_t(e)] = 1;
  }
  out.elements = int(std::count(seen.begin(), seen.end(), 1));
  hvv.diagonal().array() += 1.0 / (o_.vertex_sigma_m * o_.vertex_sigma_m);
  const Eigen::Matrix3d info = hpp - hpv * hvv.ldlt().solve(hpv.transpose());
  // Unconstrained (a lone wall, nothing at all): the information is singular in some direction.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(info);
  if (out.points < 3 || !(es.eigenvalues()(0) > 1e-9 * std::max(1.0, es.eigenvalues()(2)))) return out;
  out.cov = info.inverse();
  return out;
}

ScanBound asbuilt_scan_bound(const FloorPlan& plan, const Eigen::Vector3d& pose, const std::vector<V2>& points,
                             const AsBuiltBoundOptions& o) {
  AsBuiltBound b(plan, o);
  return b.bound(b.add_scan(pose, points));
}

}  // namespace fploc::eval
