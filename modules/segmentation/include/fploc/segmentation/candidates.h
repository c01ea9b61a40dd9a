// The points offered to a plane fit: the upper (ceiling) or lower (ground) half rings of one scan, ring by
// ring from the outermost, each ring in staggered column order. Filled by Segmenter's point preparation.
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace fploc::seg {

// Points as three float arrays (the plane fit's vectorised passes), padded after the last point to a
// multiple of 4 (pad(): NaN by default, a NaN residual drops out of every masked sum).
struct PointsSoa {
  std::vector<float> x, y, z;
  size_t n = 0;  // points (without the padding)
  size_t padded() const { return x.size(); }
  void resize(size_t m) {
    n = m;
    const size_t p = (m + 3) & ~size_t(3);
    x.resize(p);
    y.resize(p);
    z.resize(p);
  }
  void pad(float px = std::numeric_limits<float>::quiet_NaN(), float py = std::numeric_limits<float>::quiet_NaN(),
           float pz = std::numeric_limits<float>::quiet_NaN()) {
    for (size_t i = n; i < x.size(); ++i) {
      x[i] = px;
      y[i] = py;
      z[i] = pz;
    }
  }
};

struct Candidates {
  std::vector<Eigen::Vector3f> p;  // sensor frame
  // The same points as structure of arrays (the plane fit's vectorised passes), padded with NaN to a
  // multiple of kLanes after the last point (x.size() >= p.size()).
  static constexpr size_t kLanes = 4;
  std::vector<float> x, y, z;
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
    x.clear();
    y.clear();
    z.clear();
    range.clear();
    pixel.clear();
    ring_start.assign(1, 0);
    width = w;
  }
};

}  // namespace fploc::seg
