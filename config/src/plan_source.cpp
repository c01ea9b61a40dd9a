#include "fploc/config/plan_source.h"

#include <stdexcept>
#include <vector>

namespace fploc::config {

LocalizationMap load_map(const PlanSource& plan, const std::string& lookup,
                         const std::function<std::string(const std::string&)>& resolve, const std::string& field) {
  if (plan.file().empty()) throw std::runtime_error(field + ".file: no floor plan given");
  const std::vector<std::string> layers(plan.layers().begin(), plan.layers().end());
  return load_localization_map(resolve(plan.file()), layers, plan.units(), lookup.empty() ? "annf-exact" : lookup);
}

}  // namespace fploc::config
