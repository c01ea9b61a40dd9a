#include "fploc/floorplan/free_space.h"

#include <cmath>

namespace fploc {

FreeSpace::FreeSpace(const OccupancyGrid& g) : field_(g, kMaxClearanceM) {
  known_free_.assign(size_t(g.width) * size_t(g.height), 0);
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      const bool f = g.at(i, j) >= 0 && !g.occupied(i, j);
      known_free_[size_t(j) * size_t(g.width) + size_t(i)] = f;
      free_cells_ += f;
    }
}

bool FreeSpace::free(const Eigen::Vector2d& p, double clearance_m) const {
  if (known_free_.empty()) return false;
  const Eigen::Vector2d c = field_.to_cell(p);
  if (!c.allFinite()) return false;
  const long i = std::lround(c.x()), j = std::lround(c.y());
  if (i < 0 || j < 0 || i >= field_.width() || j >= field_.height()) return false;
  if (!known_free_[size_t(j) * size_t(field_.width()) + size_t(i)]) return false;
  return field_.nearest(p) > clearance_m;
}

}  // namespace fploc
