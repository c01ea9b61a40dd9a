// The seed rings' sector maxima ordered by range, largest first (RingPlaneFit::pick_seeds; internal header).
// Sorted with each range beside its candidate index: the same comparisons as sorting the indices by a look-up of
// their ranges, so the same order, ties included (std::sort's order of equal ranges), without a look-up per
// comparison.
#pragma once
#include <algorithm>
#include <vector>

namespace fploc::seg::seeds {

// keys: {range, index} (RingPlaneFit::SeedKey: the candidate's range and index), sorted in place.
template <class Key>
void sort_by_range(std::vector<Key>& keys) {
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) { return a.range > b.range; });
}

}  // namespace fploc::seg::seeds
