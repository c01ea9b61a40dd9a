// The points offered to a plane fit: the upper (ceiling) or lower (ground) half rings of one scan, ring by
// ring from the outermost, each ring in staggered column order. Filled by Segmenter's point preparation.
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace fploc::seg {

struct Candidates {
  std::vector<Eigen::Vector3f> p;  // sensor frame
  std::vector<float> range;
  std::vector<int32_t> pixel;      // row-major pixel index in the scan
  std::vector<int32_t> ring_start; // ring_start[k]..ring_start[k+1] = k-th ring from the outermost
  int width = 0;                   // columns of the scan (pixel % width = staggered column)
  // How a fit samples these points, from the beam pattern (beam_scaling.h); 0 = the fit's reference values.
  int seed_rings = 0;
  size_t start_stride = 0, final_stride = 0;
  int rings() const { return int(ring_start.size()) - 1; }
  void clear(int w) {
    p.clear();
    range.clear();
    pixel.clear();
    ring_start.assign(1, 0);
    width = w;
  }
};

}  // namespace fploc::seg
