#include "fploc/floorplan/distance_field.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fploc {

DistanceField::DistanceField(const OccupancyGrid& g, double max_m)
    : w_(g.width), h_(g.height), res_(g.resolution), max_m_(max_m), ox_(g.origin_x), oy_(g.origin_y),
      oyaw_(g.origin_yaw) {
  if (w_ <= 0 || h_ <= 0 || !(res_ > 0)) throw std::invalid_argument(g.source + ": empty occupancy grid");
  if (!(max_m > 0)) throw std::invalid_argument("distance field: max_m must be > 0");
  d_.assign(size_t(w_) * size_t(h_), float(max_m));
  const int r = int(std::ceil(max_m / res_));
  // Disc offsets with their distances, computed once.
  std::vector<std::pair<int, int>> off;
  std::vector<float> dist;
  for (int dj = -r; dj <= r; ++dj)
    for (int di = -r; di <= r; ++di) {
      const double d = std::hypot(di, dj) * res_;
      if (d <= max_m) {
        off.emplace_back(di, dj);
        dist.push_back(float(d));
      }
    }
  for (int j = 0; j < h_; ++j)
    for (int i = 0; i < w_; ++i) {
      if (!g.occupied(i, j)) continue;
      ++occupied_;
      for (size_t k = 0; k < off.size(); ++k) {
        const int a = i + off[k].first, b = j + off[k].second;
        if (a < 0 || b < 0 || a >= w_ || b >= h_) continue;
        float& c = d_[size_t(b) * size_t(w_) + size_t(a)];
        c = std::min(c, dist[k]);
      }
    }
}

Eigen::Vector2d DistanceField::to_cell(const Eigen::Vector2d& p) const {
  const double dx = p.x() - ox_, dy = p.y() - oy_;
  const double c = std::cos(oyaw_), s = std::sin(oyaw_);
  // Map frame (rotated by origin yaw), then cell centres at (i + 0.5) * res.
  const double mx = c * dx + s * dy, my = -s * dx + c * dy;
  return {mx / res_ - 0.5, my / res_ - 0.5};
}

float DistanceField::nearest(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d c = to_cell(p);
  return at(int(std::lround(c.x())), int(std::lround(c.y())));
}

}  // namespace fploc
