// Synthetic occupancy grids for the laser2d tests: an empty grid (5 cm cells, origin at (-1, -1)), walls drawn
// point by point, and a beam cast to the first occupied cell.
#pragma once
#include <cmath>
#include <limits>

#include "fploc/floorplan/occupancy.h"

namespace fploc::laser2d::test {

inline OccupancyGrid blank_grid(int width, int height) {
  OccupancyGrid g;
  g.width = width;
  g.height = height;
  g.resolution = 0.05;
  g.origin_x = -1;
  g.origin_y = -1;
  g.data.assign(size_t(g.width) * g.height, 0);
  return g;
}

// The cell holding (x, y); false outside the grid.
inline bool cell_of(const OccupancyGrid& g, double x, double y, int* i, int* j) {
  *i = int(std::floor((x - g.origin_x) / g.resolution));
  *j = int(std::floor((y - g.origin_y) / g.resolution));
  return *i >= 0 && *j >= 0 && *i < g.width && *j < g.height;
}

// Marks the cell holding (x, y) occupied (nothing outside the grid).
inline void occupy(OccupancyGrid& g, double x, double y) {
  int i, j;
  if (cell_of(g, x, y, &i, &j)) g.data[size_t(j) * g.width + i] = 100;
}

// Distance from (x, y) along angle a to the first occupied cell, in 1 cm steps from 0.1 m; infinity when the
// beam leaves the grid or reaches max_d first.
inline double first_hit(const OccupancyGrid& g, double x, double y, double a, double max_d) {
  for (double d = 0.1; d < max_d; d += 0.01) {
    int i, j;
    if (!cell_of(g, x + d * std::cos(a), y + d * std::sin(a), &i, &j)) break;
    if (g.occupied(i, j)) return d;
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace fploc::laser2d::test
