// Baselines the ANNF is measured against (fploc map validate, annf_bench):
//  - brute force: nearest_element_brute_force() in fploc/floorplan/plan.h;
//  - SampledKdTree: a nanoflann KD-tree over points sampled on the elements every `spacing` metres
//    (the point-to-point registration of the paper's eq. 2); returns the element of the nearest sample;
//  - DistanceGrid: a plain grid (distance transform) storing, per cell, the distance from the cell
//    centre to the nearest element and that element's id; a read is one memory access (the floor).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "fploc/annf/annf.h"
#include "fploc/floorplan/plan.h"

namespace fploc::annf {

class SampledKdTree {
 public:
  SampledKdTree(const FloorPlan& plan, double spacing);
  ~SampledKdTree();
  SampledKdTree(const SampledKdTree&) = delete;
  SampledKdTree& operator=(const SampledKdTree&) = delete;
  // Element id of the nearest sample point; *dist = distance to that sample point.
  int nearest(const Eigen::Vector2d& p, double* dist = nullptr) const;
  size_t points() const;
  size_t bytes() const;  // sample points + ids + tree index (approximate for the index)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class DistanceGrid {
 public:
  // Cells of `resolution` metres over the plan's bounding box; values from the exact field (so
  // they are exact at each cell centre). `exact` must be built in AnnfMode::kExact.
  DistanceGrid(const Annf& exact, double resolution);
  // Nearest element id stored for p's cell (and its centre distance); -1 outside.
  int read(const Eigen::Vector2d& p, float* dist = nullptr) const {
    const double fx = (p.x() - ox_) * inv_, fy = (p.y() - oy_) * inv_;
    if (!(fx >= 0 && fy >= 0 && fx < double(nx_) && fy < double(ny_))) return -1;
    const Cell& c = cells_[size_t(uint32_t(fy)) * nx_ + uint32_t(fx)];
    if (dist) *dist = c.dist;
    return int(c.id);
  }
  size_t bytes() const { return cells_.size() * sizeof(Cell); }
  uint32_t nx() const { return nx_; }
  uint32_t ny() const { return ny_; }
  double resolution() const { return res_; }
  Eigen::Vector2d origin() const { return {ox_, oy_}; }
  float cell_distance(uint32_t i, uint32_t j) const { return cells_[size_t(j) * nx_ + i].dist; }

 private:
  struct Cell {
    float dist;
    uint32_t id;
  };
  double ox_ = 0, oy_ = 0, res_ = 1, inv_ = 1;
  uint32_t nx_ = 0, ny_ = 0;
  std::vector<Cell> cells_;
};

}  // namespace fploc::annf