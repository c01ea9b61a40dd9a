#include "fploc/eval/asbuilt_bound.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace fploc::eval {
namespace {

using V2 = Eigen::Vector2d;

// One displacement's identity. The simulator's joints: segment ends that coincide to the millimetre (modules/sim
// perturb.cpp); a pillar's centre: its element index.
using DisplacementKey = std::tuple<int, long, long>;
DisplacementKey joint(const V2& p) { return {0, std::lround(p.x() * 1000), std::lround(p.y() * 1000)}; }
DisplacementKey pillar(size_t element) { return {1, long(element), 0}; }

}  // namespace

ScanBound asbuilt_scan_bound(const FloorPlan& plan, const Eigen::Vector3d& pose, const std::vector<V2>& points,
                             const AsBuiltBoundOptions& o) {
  if (!(o.vertex_sigma_m > 0) || !(o.point_sigma_m > 0))
    throw std::invalid_argument("asbuilt_scan_bound: vertex_sigma_m and point_sigma_m must be > 0");
  const double gate = o.gate_m > 0 ? o.gate_m : std::max(0.08, 4 * o.vertex_sigma_m);
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  const V2 sensor = pose.head<2>();

  // Each point's row: d(residual)/d(pose) (3) and its share of at most two displacements (an element's two
  // vertices, or a pillar's centre), each a 2-vector.
  struct Row {
    Eigen::Vector3d jp;
    int v[2] = {-1, -1};
    V2 dv[2] = {V2::Zero(), V2::Zero()};
  };
  std::vector<Row> rows;
  rows.reserve(points.size());
  std::map<DisplacementKey, int> index;  // a displacement's 2-column block
  auto vid = [&](const DisplacementKey& k) { return index.try_emplace(k, int(index.size())).first->second; };
  std::vector<char> seen(plan.elements.size(), 0);
  for (const V2& q : points) {
    if (!q.allFinite()) continue;
    const V2 p = sensor + V2(c * q.x() - s * q.y(), s * q.x() + c * q.y());
    size_t best = plan.elements.size();
    double bd = gate;
    for (size_t i = 0; i < plan.elements.size(); ++i) {
      const double d = distance(plan.elements[i], p);
      if (d < bd) bd = d, best = i;
    }
    if (best == plan.elements.size()) continue;
    const Element& e = plan.elements[best];
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
    const V2 rel = p - sensor;
    r.jp = Eigen::Vector3d(n.x(), n.y(), n.x() * -rel.y() + n.y() * rel.x());
    rows.push_back(r);
    seen[best] = 1;
  }
  const int nv = int(index.size());

  ScanBound out;
  out.points = int(rows.size());
  out.elements = int(std::count(seen.begin(), seen.end(), 1));
  const double wp = 1.0 / (o.point_sigma_m * o.point_sigma_m);
  Eigen::Matrix3d hpp = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd hpv = Eigen::MatrixXd::Zero(3, 2 * nv), hvv = Eigen::MatrixXd::Zero(2 * nv, 2 * nv);
  for (const Row& r : rows) {
    hpp += wp * r.jp * r.jp.transpose();
    for (int a = 0; a < 2; ++a) {
      if (r.v[a] < 0) continue;
      hpv.middleCols<2>(2 * r.v[a]) += wp * r.jp * r.dv[a].transpose();
      for (int b = 0; b < 2; ++b)
        if (r.v[b] >= 0) hvv.block<2, 2>(2 * r.v[a], 2 * r.v[b]) += wp * r.dv[a] * r.dv[b].transpose();
    }
  }
  hvv.diagonal().array() += 1.0 / (o.vertex_sigma_m * o.vertex_sigma_m);
  const Eigen::Matrix3d info = hpp - hpv * hvv.ldlt().solve(hpv.transpose());
  // Unconstrained (a lone wall, nothing at all): the information is singular in some direction.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(info);
  if (rows.size() < 3 || !(es.eigenvalues()(0) > 1e-9 * std::max(1.0, es.eigenvalues()(2)))) return out;
  out.cov = info.inverse();
  return out;
}

}  // namespace fploc::eval
