// Where an occupancy map says there is nothing: its known-free cells, with their distance to the nearest
// occupied cell. A scan point that lands there, farther than a clearance from any occupied cell, contradicts
// the map at that pose; a point in unknown space or off the map does not (the map has no opinion there). A
// plan vectorised from the map keeps only the occupied boundaries, so this is what the map adds to it: the
// difference between "the map lacks that wall" (a room it saw only in part) and "the map says it is empty
// there" (the pose is wrong, or the building changed).
//
//   FreeSpace fs(read_occupancy_map("map.yaml"));
//   bool contradicts = fs.free(point_in_world, 0.1);
//
// Known free: a cell with a value (not -1) that is not occupied (OccupancyGrid::occupied). Distances as
// DistanceField's (cell centres, exact within the truncation max_clearance_m).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fploc/floorplan/distance_field.h"
#include "fploc/floorplan/occupancy.h"

namespace fploc {

class FreeSpace {
 public:
  static constexpr double kMaxClearanceM = 0.5;  // the largest clearance free() can be asked for
  FreeSpace() = default;
  explicit FreeSpace(const OccupancyGrid& g);

  // Whether the map says the world point p is empty: its cell is known free and p is more than clearance_m
  // (<= kMaxClearanceM) from every occupied cell centre. False off the map and in unknown cells.
  bool free(const Eigen::Vector2d& p, double clearance_m) const;
  // Whether the map has an opinion at p at all: its cell is known (free or occupied), not unknown or off the map.
  bool known(const Eigen::Vector2d& p) const { return state(p) != kUnknown; }
  size_t free_cells() const { return free_cells_; }

 private:
  enum CellState : uint8_t { kUnknown = 0, kOccupied = 1, kFree = 2 };
  // p's cell (index into state_) and its state; kUnknown off the map or for a non-finite p.
  CellState state(const Eigen::Vector2d& p, size_t* cell = nullptr) const;
  DistanceField field_;
  std::vector<uint8_t> state_;  // CellState per cell, row-major, row 0 bottom (as the grid)
  size_t free_cells_ = 0;
};

}  // namespace fploc
