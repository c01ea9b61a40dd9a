#include "fploc/ndt/plan_cloud.h"

#include <cmath>
#include <stdexcept>

namespace fploc::ndt {

std::vector<Eigen::Vector3f> plan_cloud(const FloorPlan& plan, const PlanCloudOptions& o) {
  if (!(o.spacing_m > 0)) throw std::invalid_argument("plan cloud: spacing_m must be > 0");
  if (!(o.z_max_m > o.z_min_m)) throw std::invalid_argument("plan cloud: z_max_m must be above z_min_m");
  std::vector<Eigen::Vector2d> xy;
  for (const auto& e : plan.elements) {
    if (e.kind == ElementKind::kSegment) {
      const double len = (e.b - e.a).norm();
      const int n = std::max(1, int(std::ceil(len / o.spacing_m)));
      for (int i = 0; i <= n; ++i) xy.push_back(e.a + (e.b - e.a) * (double(i) / n));
    } else {
      const double a0 = e.kind == ElementKind::kCircle ? 0.0 : e.a0;
      const double a1 = e.kind == ElementKind::kCircle ? 2 * M_PI : e.a1;
      const int n = std::max(3, int(std::ceil(e.r * (a1 - a0) / o.spacing_m)));
      const int last = e.kind == ElementKind::kCircle ? n - 1 : n;
      for (int i = 0; i <= last; ++i) {
        const double a = a0 + (a1 - a0) * double(i) / n;
        xy.push_back(e.c + e.r * Eigen::Vector2d(std::cos(a), std::sin(a)));
      }
    }
  }
  const int nz = std::max(1, int(std::floor((o.z_max_m - o.z_min_m) / o.spacing_m + 1e-9)));
  std::vector<Eigen::Vector3f> out;
  out.reserve(xy.size() * size_t(nz + 1));
  for (const auto& p : xy)
    for (int k = 0; k <= nz; ++k)
      out.emplace_back(float(p.x()), float(p.y()), float(o.z_min_m + (o.z_max_m - o.z_min_m) * k / nz));
  return out;
}

}  // namespace fploc::ndt
