#include "fploc/matcher/free_space_check.h"

#include <cmath>

namespace fploc::matcher {

double contradicted_share(const FreeSpace& free_space, const FeatureFrame& f, const Pose2& x, double clearance_m,
                          double inlier_ratio) {
  if (f.points.empty()) return 0.0;
  const double c = std::cos(x.yaw), s = std::sin(x.yaw);
  size_t in_free = 0;
  for (const auto& q : f.points) {
    const Eigen::Vector2d w(x.x + c * q.p.x() - s * q.p.y(), x.y + s * q.p.x() + c * q.p.y());
    in_free += free_space.free(w, clearance_m);
  }
  const double free_share = double(in_free) / double(f.points.size());
  return free_share + inlier_ratio > 0 ? free_share / (free_share + inlier_ratio) : 0.0;
}

}  // namespace fploc::matcher
