// A raster of an occupancy grid (ROS map_server, occupancy.h): the Euclidean distance from every cell to the
// nearest occupied cell centre, truncated at max_m. The 2D mode's grid localizer (laser2d/grid_localizer.h)
// scores and refines planar scans on it, instead of on the plan that the vectorisation of the same grid gives
// (its segments cut corners by up to half a cell and split at every unknown cell; the field keeps every
// occupied cell as it was measured); FreeSpace (free_space.h) measures clearances on it.
//
// Built by stamping: every occupied cell writes its distance into the cells of a disc of radius max_m
// around it (min over stamps), i.e. exact within the truncation. Row 0 is the bottom row (y = origin_y), as
// in nav_msgs/OccupancyGrid. A rotated map (origin yaw != 0) is handled by rotating queries.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fploc/floorplan/occupancy.h"

namespace fploc {

class DistanceField {
 public:
  DistanceField() = default;
  DistanceField(const OccupancyGrid& g, double max_m);

  int width() const { return w_; }
  int height() const { return h_; }
  double resolution() const { return res_; }
  double max_distance() const { return max_m_; }
  size_t occupied_cells() const { return occupied_; }
  // Continuous cell coordinates (cell (i, j)'s centre at (i, j)) of a world point.
  Eigen::Vector2d to_cell(const Eigen::Vector2d& p) const;
  // Distance [m] stored at cell (i, j) (max_m off the map).
  float at(int i, int j) const {
    return (i < 0 || j < 0 || i >= w_ || j >= h_) ? float(max_m_) : d_[size_t(j) * size_t(w_) + size_t(i)];
  }
  // Nearest-cell distance of a world point.
  float nearest(const Eigen::Vector2d& p) const;
  const std::vector<float>& data() const { return d_; }  // row-major, row 0 bottom
  // World <-> map frame (origin yaw).
  double origin_x() const { return ox_; }
  double origin_y() const { return oy_; }
  double origin_yaw() const { return oyaw_; }

 private:
  int w_ = 0, h_ = 0;
  double res_ = 0.05, max_m_ = 1.0, ox_ = 0, oy_ = 0, oyaw_ = 0;
  size_t occupied_ = 0;
  std::vector<float> d_;
};

}  // namespace fploc
