#include "fploc/annf/baselines.h"

#include <cmath>
#include <nanoflann.hpp>
#include <stdexcept>

namespace fploc::annf {

struct SampledKdTree::Impl {
  struct Cloud {
    std::vector<Eigen::Vector2d> pts;
    size_t kdtree_get_point_count() const { return pts.size(); }
    double kdtree_get_pt(size_t i, size_t d) const { return pts[i][int(d)]; }
    template <class B>
    bool kdtree_get_bbox(B&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2, uint32_t>;
  Cloud cloud;
  std::vector<uint32_t> ids;
  std::unique_ptr<Tree> tree;
};

SampledKdTree::SampledKdTree(const FloorPlan& plan, double spacing) : impl_(std::make_unique<Impl>()) {
  if (!(spacing > 0)) throw std::runtime_error("KD-tree sample spacing must be > 0");
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    const Element& e = plan.elements[i];
    std::vector<Eigen::Vector2d> s;
    if (e.kind == ElementKind::kSegment) {
      const double len = (e.b - e.a).norm();
      const int n = std::max(1, int(std::ceil(len / spacing)));
      for (int k = 0; k <= n; ++k) s.push_back(e.a + (e.b - e.a) * (double(k) / n));
    } else {
      const double sweep = e.a1 - e.a0;
      const int n = std::max(e.kind == ElementKind::kCircle ? 4 : 1, int(std::ceil(sweep * e.r / spacing)));
      const int last = e.kind == ElementKind::kCircle ? n - 1 : n;
      for (int k = 0; k <= last; ++k) {
        const double t = e.a0 + sweep * k / n;
        s.push_back(e.c + e.r * Eigen::Vector2d(std::cos(t), std::sin(t)));
      }
    }
    for (const auto& p : s) {
      impl_->cloud.pts.push_back(p);
      impl_->ids.push_back(uint32_t(i));
    }
  }
  impl_->tree = std::make_unique<Impl::Tree>(2, impl_->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  impl_->tree->buildIndex();
}

SampledKdTree::~SampledKdTree() = default;

int SampledKdTree::nearest(const Eigen::Vector2d& p, double* dist) const {
  uint32_t idx = 0;
  double d2 = 0;
  const double q[2] = {p.x(), p.y()};
  if (impl_->tree->knnSearch(q, 1, &idx, &d2) == 0) return -1;
  if (dist) *dist = std::sqrt(d2);
  return int(impl_->ids[idx]);
}

size_t SampledKdTree::points() const { return impl_->cloud.pts.size(); }
size_t SampledKdTree::bytes() const {
  // points + ids + index permutation + ~2 nodes per leaf of 10 (nanoflann node ~ 40 B)
  const size_t n = impl_->cloud.pts.size();
  return n * (sizeof(Eigen::Vector2d) + 2 * sizeof(uint32_t)) + (n / 5 + 1) * 40;
}

DistanceGrid::DistanceGrid(const Annf& exact, double resolution) {
  if (!(resolution > 0)) throw std::runtime_error("grid resolution must be > 0");
  if (exact.options().mode != AnnfMode::kExact) throw std::runtime_error("DistanceGrid needs an exact-mode ANNF");
  const Box2 b = exact.plan().bounds();
  res_ = resolution;
  inv_ = 1.0 / resolution;
  ox_ = b.min.x();
  oy_ = b.min.y();
  const double nx = std::ceil(b.size().x() / resolution) + 1, ny = std::ceil(b.size().y() / resolution) + 1;
  if (nx * ny > 4e8) throw std::runtime_error("distance grid too large");
  nx_ = uint32_t(nx);
  ny_ = uint32_t(ny);
  cells_.resize(size_t(nx_) * ny_);
  for (uint32_t j = 0; j < ny_; ++j)
    for (uint32_t i = 0; i < nx_; ++i) {
      double d;
      const int id = exact.nearest(Eigen::Vector2d(ox_ + (i + 0.5) * res_, oy_ + (j + 0.5) * res_), &d);
      cells_[size_t(j) * nx_ + i] = {float(d), uint32_t(id)};
    }
}

}  // namespace fploc::annf