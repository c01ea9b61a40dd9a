#pragma once
#include <vector>

#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"

namespace fploc::seg::test_util {

struct WallStats {
  double precision = 0, recall = 0;
  size_t returned = 0, plan_walls = 0;
};

// Precision: returned wall points that are not ceiling/floor returns. Recall: plan wall/pillar returns
// kept. Needs the segmenter's per-pixel labels (set_keep_labels(true)).
inline WallStats wall_stats(const Segmentation& out, const std::vector<uint8_t>& truth) {
  WallStats s;
  size_t bad = 0, kept = 0;
  for (size_t i = 0; i < truth.size() && i < out.label.size(); ++i) {
    const bool wall = out.label[i] == 3;
    if (wall) {
      ++s.returned;
      bad += truth[i] == synth::kCeiling || truth[i] == synth::kFloor;
    }
    if (truth[i] == synth::kWall) {
      ++s.plan_walls;
      kept += wall;
    }
  }
  s.precision = s.returned ? 1.0 - double(bad) / s.returned : 0.0;
  s.recall = s.plan_walls ? double(kept) / s.plan_walls : 0.0;
  return s;
}

}  // namespace fploc::seg::test_util
