#include "fploc/localizer/active_plan.h"

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

}  // namespace fploc::localizer
