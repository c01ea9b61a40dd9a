#include "fploc/matcher/element_weights.h"

#include <algorithm>
#include <cmath>

namespace fploc::matcher {

std::vector<int> wall_twins(const FloorPlan& plan, double max_gap) {
  const auto& els = plan.elements;
  std::vector<int> twin(els.size(), -1);
  for (size_t i = 0; i < els.size(); ++i) {
    const Element& e = els[i];
    if (e.kind != ElementKind::kSegment) continue;
    const Eigen::Vector2d d = e.b - e.a;
    const double L = d.norm();
    if (L < 1e-9) continue;
    const Eigen::Vector2d u = d / L;
    double best_d = max_gap;
    for (size_t j = 0; j < els.size(); ++j) {
      const Element& f = els[j];
      if (j == i || f.kind != ElementKind::kSegment) continue;
      const Eigen::Vector2d fd = f.b - f.a;
      const double fl = fd.norm();
      if (fl < 1e-9 || std::abs(u.x() * fd.y() / fl - u.y() * fd.x() / fl) > 0.05) continue;
      const Eigen::Vector2d m = 0.5 * (f.a + f.b) - e.a;
      const double gap = std::abs(u.x() * m.y() - u.y() * m.x());
      if (gap < 0.02 || gap >= best_d) continue;
      double s0 = u.dot(f.a - e.a), s1 = u.dot(f.b - e.a);
      if (s0 > s1) std::swap(s0, s1);
      if (std::min(s1, L) - std::max(s0, 0.0) < 0.5 * std::min(L, s1 - s0)) continue;
      best_d = gap;
      twin[i] = int(j);
    }
  }
  return twin;
}

namespace {
std::vector<float> weights_with(const FloorPlan& plan, const std::vector<int>& twins,
                                const std::vector<FlaggedElement>& flagged, const DiffWeightOptions& o) {
  std::vector<float> w(plan.elements.size(), 1.0f);
  auto set = [&](int id, float v) {
    if (id >= 0 && size_t(id) < w.size()) w[size_t(id)] = std::min(w[size_t(id)], v);
  };
  for (const auto& f : flagged) {
    if (f.id < 0 || size_t(f.id) >= w.size()) continue;
    const float v = std::max(0.0f, f.verdict == DiffVerdict::kMissing ? o.missing_weight : o.moved_weight);
    set(f.id, v);
    if (o.twins) set(twins[size_t(f.id)], v);
  }
  return w;
}
}  // namespace

std::vector<float> element_weights(const FloorPlan& plan, const std::vector<FlaggedElement>& flagged,
                                   const DiffWeightOptions& o) {
  return weights_with(plan, o.twins ? wall_twins(plan, o.twin_max_gap_m) : std::vector<int>(plan.elements.size(), -1),
                      flagged, o);
}

ElementWeights::ElementWeights(const FloorPlan& plan, DiffWeightOptions o)
    : plan_(plan), o_(o), twins_(wall_twins(plan, o.twin_max_gap_m)), w_(plan.elements.size(), 1.0f) {}

bool ElementWeights::update(const std::vector<FlaggedElement>& flagged) {
  std::vector<float> w = weights_with(plan_, twins_, flagged, o_);
  if (w == w_) return false;
  w_ = std::move(w);
  flagged_ = int(std::count_if(w_.begin(), w_.end(), [](float v) { return v < 1.0f; }));
  return true;
}

}  // namespace fploc::matcher
