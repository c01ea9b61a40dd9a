#include "fploc/matcher/plan_scale.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fploc::matcher {

Eigen::Vector2d scale_centre(const FloorPlan& plan) {
  const Box2 b = plan.bounds();
  return 0.5 * (b.min + b.max);
}

FloorPlan scaled_plan(const FloorPlan& plan, double factor, const Eigen::Vector2d& centre) {
  FloorPlan out = plan;
  for (auto& e : out.elements) {
    e.a = centre + factor * (e.a - centre);
    e.b = centre + factor * (e.b - centre);
    e.c = centre + factor * (e.c - centre);
    e.r *= factor;
  }
  return out;
}

Pose2 rescaled_pose(const Pose2& p, double f0, double f1, const Eigen::Vector2d& centre) {
  const double k = f1 / f0;
  return {centre.x() + k * (p.x - centre.x()), centre.y() + k * (p.y - centre.y()), p.yaw};
}

LocalizationMap scaled_localization_map(const FloorPlan& plan, double scale_error, const std::string& lookup) {
  return make_localization_map(scaled_plan(plan, 1 + scale_error, scale_centre(plan)), lookup.empty() ? "annf-exact" : lookup);
}

FloorPlan offset_plan(const FloorPlan& plan, const std::vector<SegmentOffset>& offsets) {
  FloorPlan out = plan;
  for (const auto& o : offsets) {
    if (o.element < 0 || size_t(o.element) >= out.elements.size()) continue;
    Element& e = out.elements[size_t(o.element)];
    if (e.kind != ElementKind::kSegment) continue;
    const Eigen::Vector2d d = e.b - e.a;
    if (d.norm() < 1e-9) continue;
    const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized();
    e.a += o.offset_a * n;
    e.b += o.offset_b * n;
  }
  return out;
}

FloorPlan corrected_plan(const FloorPlan& plan, double scale_error, const std::vector<SegmentOffset>& offsets) {
  FloorPlan p = offsets.empty() ? plan : offset_plan(plan, offsets);
  return scale_error == 0 ? p : scaled_plan(p, 1 + scale_error, scale_centre(plan));
}

LocalizationMap corrected_localization_map(const FloorPlan& plan, double scale_error, const std::vector<SegmentOffset>& offsets,
                                           const std::string& lookup) {
  return make_localization_map(corrected_plan(plan, scale_error, offsets), lookup.empty() ? "annf-exact" : lookup);
}

bool RefineCorrection::update(const std::vector<SegmentOffset>& offsets, int64_t utime) {
  if (offsets.empty()) return false;
  if (have_ && (utime - last_utime_) * 1e-6 < o_.min_interval_s) return false;
  double change = 0;
  auto find = [](const std::vector<SegmentOffset>& v, int id) -> const SegmentOffset* {
    for (const auto& x : v)
      if (x.element == id) return &x;
    return nullptr;
  };
  for (const auto& o : offsets) {
    const SegmentOffset* a = find(applied_, o.element);
    change = std::max({change, std::abs(o.offset_a - (a ? a->offset_a : 0.0)), std::abs(o.offset_b - (a ? a->offset_b : 0.0))});
  }
  for (const auto& a : applied_)
    if (!find(offsets, a.element)) change = std::max({change, std::abs(a.offset_a), std::abs(a.offset_b)});
  if (change < o_.min_change_m) return false;
  applied_ = offsets;
  last_utime_ = utime;
  have_ = true;
  return true;
}

std::optional<double> ScaleCorrection::update(double error, double sigma) {
  if (!std::isfinite(error) || !std::isfinite(sigma) || sigma <= 0) return std::nullopt;
  // Significant: apply. Once applied, it stays while the estimate keeps half the significance (no
  // toggling on an estimate hovering at the threshold).
  const bool applied = applied_ != 0;
  const double need = applied ? 0.5 : 1.0;
  const bool significant = std::abs(error) >= need * o_.min_error && std::abs(error) >= need * o_.min_sigmas * sigma;
  const double target = significant ? error : 0.0;
  if (target == applied_) return std::nullopt;
  if (target != 0 && applied && std::abs(target - applied_) < std::max(o_.min_change, o_.change_sigmas * sigma))
    return std::nullopt;
  applied_ = target;
  return applied_;
}

std::unique_ptr<LocalizationMap> PlanCorrection::update(const FloorPlan& plan, double scale_error, double scale_sigma,
                                                       const std::vector<SegmentOffset>& offsets, int64_t utime,
                                                       const std::string& lookup, std::string* said) {
  const bool scaled = scale_on_ && scale_.update(scale_error, scale_sigma).has_value();
  const bool refined = refine_on_ && refine_.update(offsets, utime);
  if (!scaled && !refined) return nullptr;
  if (said) {
    double worst = 0;
    for (const auto& o : refine_.applied()) worst = std::max({worst, std::abs(o.offset_a), std::abs(o.offset_b)});
    char buf[200];
    int k = std::snprintf(buf, sizeof buf, "plan corrected: scale %+.3f %% (estimate %+.3f +- %.3f %%)",
                          100 * scale_.applied(), 100 * scale_error, 100 * scale_sigma);
    if (refine_on_ && k > 0 && size_t(k) < sizeof buf)
      std::snprintf(buf + k, sizeof buf - size_t(k), ", %zu walls refined (up to %.1f cm)", refine_.applied().size(),
                    100 * worst);
    *said = buf;
  }
  return std::make_unique<LocalizationMap>(corrected_localization_map(plan, scale_.applied(), refine_.applied(), lookup));
}

}  // namespace fploc::matcher
