#include "fploc/floorplan/free_space.h"

#include <cmath>

namespace fploc {

FreeSpace::FreeSpace(const OccupancyGrid& g) : field_(g, kMaxClearanceM) {
  state_.assign(size_t(g.width) * size_t(g.height), kUnknown);
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      const CellState c = g.at(i, j) < 0 ? kUnknown : g.occupied(i, j) ? kOccupied : kFree;
      state_[size_t(j) * size_t(g.width) + size_t(i)] = c;
      free_cells_ += c == kFree;
    }
}

FreeSpace::CellState FreeSpace::state(const Eigen::Vector2d& p, size_t* cell) const {
  if (state_.empty()) return kUnknown;
  const Eigen::Vector2d c = field_.to_cell(p);
  if (!c.allFinite()) return kUnknown;
  const long i = std::lround(c.x()), j = std::lround(c.y());
  if (i < 0 || j < 0 || i >= field_.width() || j >= field_.height()) return kUnknown;
  const size_t k = size_t(j) * size_t(field_.width()) + size_t(i);
  if (cell) *cell = k;
  return CellState(state_[k]);
}

bool FreeSpace::free(const Eigen::Vector2d& p, double clearance_m) const {
  size_t k = 0;
  if (state(p, &k) != kFree) return false;
  return field_.data()[k] > clearance_m;  // the field's cell of p (the same rounding), without a second look-up
}

}  // namespace fploc
