#include "fploc/matcher/lookup.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>

namespace fploc::matcher {

const std::vector<TargetGeom>& NearestLookup::geometry() const {
  std::call_once(geom_once_, [this] {
    const auto& t = targets();
    geom_.resize(t.size());
    for (size_t i = 0; i < t.size(); ++i) {
      const Element& e = t[i];
      TargetGeom& g = geom_[i];
      g.kind = e.kind;
      g.a = e.a;
      g.b = e.b;
      g.c = e.c;
      g.r = e.r;
      g.a0 = e.a0;
      g.a1 = e.a1;
      if (e.kind == ElementKind::kSegment) {
        g.len = (e.b - e.a).norm();
        if (g.len > 0) g.u = (e.b - e.a) / g.len;
      }
    }
  });
  return geom_;
}

int BruteForceLookup::candidates(const Eigen::Vector2d& p, int* out, int max) const {
  if (max <= 0) return 0;
  const int i = nearest_element_brute_force(plan_, p);
  if (i < 0) return 0;
  out[0] = i;
  return 1;
}

std::vector<Eigen::Vector2d> sample_element(const Element& e, double spacing_m) {
  std::vector<Eigen::Vector2d> out;
  spacing_m = std::max(spacing_m, 1e-3);
  switch (e.kind) {
    case ElementKind::kSegment: {
      const double len = (e.b - e.a).norm();
      const int n = std::max(1, int(std::ceil(len / spacing_m)));
      for (int i = 0; i <= n; ++i) out.push_back(e.a + (e.b - e.a) * (double(i) / n));
      break;
    }
    case ElementKind::kCircle:
    case ElementKind::kArc: {
      const double a0 = e.kind == ElementKind::kCircle ? 0.0 : e.a0;
      const double a1 = e.kind == ElementKind::kCircle ? 2 * M_PI : e.a1;
      const int n = std::max(4, int(std::ceil(e.r * (a1 - a0) / spacing_m)));
      const int last = e.kind == ElementKind::kCircle ? n - 1 : n;
      for (int i = 0; i <= last; ++i) {
        const double a = a0 + (a1 - a0) * double(i) / n;
        out.push_back(e.c + e.r * Eigen::Vector2d(std::cos(a), std::sin(a)));
      }
      break;
    }
  }
  return out;
}

struct KdTreeLookup::Impl {
  struct Cloud {
    const std::vector<Element>* pts;
    size_t kdtree_get_point_count() const { return pts->size(); }
    double kdtree_get_pt(size_t i, size_t d) const { return (*pts)[i].a[int(d)]; }
    template <class B>
    bool kdtree_get_bbox(B&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2, uint32_t>;
  Cloud cloud;
  std::unique_ptr<Tree> tree;
};

KdTreeLookup::KdTreeLookup(const FloorPlan& plan, double spacing_m) : impl_(std::make_unique<Impl>()) {
  for (const auto& e : plan.elements)
    for (const auto& p : sample_element(e, spacing_m)) samples_.push_back(Element::segment(p, p, e.layer));
  impl_->cloud.pts = &samples_;
  impl_->tree = std::make_unique<Impl::Tree>(2, impl_->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  impl_->tree->buildIndex();
}

KdTreeLookup::~KdTreeLookup() = default;

int KdTreeLookup::candidates(const Eigen::Vector2d& p, int* out, int max) const {
  if (max <= 0 || samples_.empty()) return 0;
  uint32_t idx = 0;
  double d2 = 0;
  nanoflann::KNNResultSet<double, uint32_t> rs(1);
  rs.init(&idx, &d2);
  const double q[2] = {p.x(), p.y()};
  impl_->tree->findNeighbors(rs, q, nanoflann::SearchParams());
  out[0] = int(idx);
  return 1;
}

}  // namespace fploc::matcher