// The points offered to a plane fit: the upper (ceiling) or lower (ground) half rings of one scan, ring by
// ring from the outermost, each ring in staggered column order. Filled by Segmenter's point preparation.
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace fploc::seg {

// Points as three float arrays (the vectorised passes of the plane fit), padded after the last point to a
// multiple of 4 (pad(): NaN by default; a NaN residual drops out of every masked sum).
struct PointsSoa {
  std::vector<float> x, y, z;
  size_t n = 0;  // points (without the padding)
  size_t padded() const { return (n + 3) & ~size_t(3); }
  // n = m; the arrays only grow (no re-initialisation when a later call asks for fewer points).
  void resize(size_t m) {
    n = m;
    const size_t p = padded();
    if (x.size() < p) {
      x.resize(p);
      y.resize(p);
      z.resize(p);
    }
  }
  void pad(float px = std::numeric_limits<float>::quiet_NaN(), float py = std::numeric_limits<float>::quiet_NaN(),
           float pz = std::numeric_limits<float>::quiet_NaN()) {
    for (size_t i = n, e = padded(); i < e; ++i) {
      x[i] = px;
      y[i] = py;
      z[i] = pz;
    }
  }
};

struct Candidates {
  // The first n entries of x/y/z (sensor frame), range and pixel are the points; the arrays are longer (the
  // preparation keeps them at full size from scan to scan instead of re-initialising them), and x/y/z hold
  // NaN from n up to the next multiple of kLanes at least.
  static constexpr size_t kLanes = 4;
  size_t n = 0;
  std::vector<float> x, y, z;
  std::vector<float> range;
  std::vector<int32_t> pixel;      // row-major pixel index in the scan
  std::vector<int32_t> ring_start; // ring_start[k]..ring_start[k+1] = k-th ring from the outermost
  // De-skewed scans (x/y/z rotated to mid-sweep): the same returns as measured, when has_raw (the preparation's
  // eight-lane pass writes them; the wall points are published as measured).
  bool has_raw = false;
  std::vector<float> raw_x, raw_y, raw_z;
  int width = 0;                   // columns of the scan (pixel % width = staggered column)
  // How a fit samples these points, from the beam pattern (beam_scaling.h); 0 = the fit's reference values.
  int seed_rings = 0;
  size_t start_stride = 0, final_stride = 0;
  // The same points as vectors: filled only by fill_points() (the RANSAC fit and the building-area census
  // read them; the ring fit does not).
  std::vector<Eigen::Vector3f> p;
  // Bounding boxes of the points in blocks of kBoxPoints (block k: points [k kBoxPoints, (k+1) kBoxPoints) below
  // n), as six arrays of box_stride floats: min x, y, z, max x, y, z of each block; box_r: the largest |x|,
  // |y|, |z| of the points. Valid only while box_n == n (the preparation computes them; push() and clear() drop
  // them). The plane fit's band and the plane quality skip the blocks whose box lies wholly outside what they
  // look for (the same results; see compact_kernels.h).
  static constexpr size_t kBoxPoints = 64;
  std::vector<float> box;
  size_t box_stride = 0, box_n = size_t(-1);
  float box_r = 0;
  bool has_boxes() const { return box_n == n && n > 0; }

  size_t size() const { return n; }
  int rings() const { return int(ring_start.size()) - 1; }
  Eigen::Vector3f point(size_t i) const { return {x[i], y[i], z[i]}; }
  void fill_points() {
    p.resize(n);
    for (size_t i = 0; i < n; ++i) p[i] = point(i);
  }
  // Appends one point (tests and tools building candidates by hand; keeps the padding).
  void push(const Eigen::Vector3f& q, float r, int32_t pix) {
    box_n = size_t(-1);
    has_raw = false;
    for (auto* v : {&x, &y, &z}) v->resize(n + kLanes, std::numeric_limits<float>::quiet_NaN());
    x[n] = q.x();
    y[n] = q.y();
    z[n] = q.z();
    range.resize(n + 1);
    pixel.resize(n + 1);
    range[n] = r;
    pixel[n] = pix;
    ++n;
  }
  void clear(int w) {
    n = 0;
    has_raw = false;
    box_n = size_t(-1);
    p.clear();
    x.assign(kLanes, std::numeric_limits<float>::quiet_NaN());
    y.assign(kLanes, std::numeric_limits<float>::quiet_NaN());
    z.assign(kLanes, std::numeric_limits<float>::quiet_NaN());
    range.clear();
    pixel.clear();
    ring_start.assign(1, 0);
    width = w;
  }
};

}  // namespace fploc::seg
