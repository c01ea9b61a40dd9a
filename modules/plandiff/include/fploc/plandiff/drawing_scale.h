// The drawing-scale estimate of the plan diff (Diff::scale_error / scale_sigma): every point near its wall
// gives its offset against its distance from the sensor along the wall's normal,
//   offset = s * (n . (q - sensor) - offset) + n . b,
// b the scan's registration bias. Each scan's bias is eliminated (Schur complement) and what remains is summed
// over the run, also per element, for the sigma with the walls as the independent units and for what the walls'
// own as-built offsets can fake (see estimate()).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace fploc::plandiff {

class DrawingScale {
 public:
  explicit DrawingScale(size_t elements);
  // One scan: points (of element `element`, model row (n . (q - sensor) - offset, n.x, n.y)), then end_scan().
  void add_point(int element, const Eigen::Vector3d& row, double offset);
  void end_scan();

  struct Estimate {
    double error = 0, sigma = 0;
    int64_t points = 0;  // 0: too little to tell (error and sigma 0)
  };
  // frames: every scan added (the points of one scan are not independent); min_frames: an element enters the
  // walls' own offsets only when seen in that many scans.
  Estimate estimate(int frames, int min_frames) const;

 private:
  // This scan's sums, all points and per element.
  struct ElementSums {
    int element;
    Eigen::Matrix3d A;
    Eigen::Vector3d g;
    Eigen::Vector3d a;  // sum of its rows: what a shift of the element by 1 m adds to g
    double o;           // sum of its offsets
    int n;              // its points
  };
  Eigen::Matrix3d sA_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d sg_ = Eigen::Vector3d::Zero();
  double so2_ = 0;
  int scount_ = 0;
  std::vector<ElementSums> esums_;
  std::vector<int> eslot_;  // element -> its index in esums_ (-1: none this scan)

  // The run's sums, each scan's bias eliminated.
  double h_ = 0, g_ = 0, o2_ = 0;
  int64_t n_ = 0;
  std::vector<double> eg_, eh_;  // per element: its part of g_ / h_
  // Per element, summed over its points and scans: its offsets' residual from the scale model is
  // (ep_ - s ec_) / en_ at scale s; ec_ is also d g_ / d (its offset).
  std::vector<double> ep_, ec_;
  std::vector<double> el_;  // per element: its leverage on the scans' biases, times its points (sum over scans)
  std::vector<int64_t> en_;
  std::vector<int> ef_;  // scans
};

}  // namespace fploc::plandiff
