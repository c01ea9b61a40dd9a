#include "fploc/adapters/plan_diff_t.h"

#include <algorithm>

namespace fploc::adapters {

std::vector<matcher::FlaggedElement> flagged_elements(const plan_diff_t& m) {
  std::vector<matcher::FlaggedElement> out;
  const size_t n = size_t(std::max(0, m.num_items));
  for (size_t i = 0; i < n && i < m.kind.size() && i < m.element.size(); ++i) {
    if (m.element[i] < 0) continue;
    if (m.kind[i] == 1) out.push_back({m.element[i], matcher::DiffVerdict::kMissing});
    else if (m.kind[i] == 2) out.push_back({m.element[i], matcher::DiffVerdict::kMoved});
  }
  return out;
}

}  // namespace fploc::adapters
