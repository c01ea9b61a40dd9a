#include "fploc/localizer/active_plan.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace fploc::localizer {

ActivePlan::ActivePlan(FloorMaps floors, float diff_weight, matcher::PlanCorrection correction, std::string lookup)
    : floors_(std::move(floors)), floor_(floors_.initial), diff_weight_(diff_weight), correction_(correction),
      lookup_(std::move(lookup)) {
  set_floor(floor_);
}

std::unique_ptr<Localizer> ActivePlan::make_localizer(Config cfg) const {
  cfg.matcher.element_weight = weights_->weights();
  cfg.optimizer.element_weight = weights_->weights();
  const matcher::LocalizationMap& map = corrected_ ? *corrected_ : floors_.maps[size_t(floor_)];
  use_map(cfg, map);
  return std::make_unique<Localizer>(*map.lookup, cfg);
}

void ActivePlan::set_floor(int floor) {
  floor_ = floor;
  scale_centre_ = matcher::scale_centre(plan());
  previous_weights_ = std::move(weights_);
  weights_ = std::make_unique<matcher::ElementWeights>(plan(), matcher::DiffWeightOptions{diff_weight_, diff_weight_});
}

bool ActivePlan::apply_flags(const std::vector<matcher::FlaggedElement>& flagged, std::string* error) {
  const size_t n = plan().elements.size();
  for (const auto& f : flagged)
    if (f.id < 0 || size_t(f.id) >= n) {
      *error = "element " + std::to_string(f.id) + " not in the plan (" + std::to_string(n) +
               " elements): a diff of another plan? (ignored)";
      return false;
    }
  weights_->update(flagged);
  return true;
}

bool ActivePlan::correct(double scale_error, double scale_sigma, const std::vector<matcher::SegmentOffset>& offsets,
                         int64_t utime, std::string* said, std::string* error) {
  if (std::isfinite(scale_error) && std::isfinite(scale_sigma) && scale_sigma > 0) {
    scale_estimate_ = scale_error;
    scale_sigma_ = scale_sigma;
  }
  if (!correction_.enabled()) return false;
  if (multi_floor()) {
    if (!warned_) *error = "plan_diff_scale / plan_diff_refine: not for a building of several floors (ignored)";
    warned_ = true;
    return false;
  }
  auto map = correction_.update(plan(), scale_error, scale_sigma, offsets, utime, lookup_, said);
  if (!map) return false;
  previous_corrected_ = std::move(corrected_);
  corrected_ = std::move(map);
  return true;
}

double ActivePlan::unexplained_scale_squared() const {
  if (!(scale_sigma_ > 0) || multi_floor()) return 0;
  const double left = scale_estimate_ - correction_.scale();
  return std::max(0.0, left * left - scale_sigma_ * scale_sigma_);
}

void ActivePlan::add_scale_error(Pose* pose, double s2) const {
  if (!(s2 > 0)) return;
  const Eigen::Vector2d d = Eigen::Vector2d(pose->pose.x, pose->pose.y) - scale_centre_;
  pose->covariance.topLeftCorner<2, 2>() += s2 * d * d.transpose();
}

}  // namespace fploc::localizer
