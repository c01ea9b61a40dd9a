// Per-element weights of the floor-plan terms from the plan-change detector's verdicts (issue 12,
// "the matcher down-weights elements the diff marks missing or moved"): an element the diff says is no
// longer where the plan draws it (removed, or standing 10-25 cm off) should not pull the registration
// towards the drawing. The weights go to the correspondence look-up (AssignOptions::element_weight):
// elements of weight 0 are no candidates at all, others scale their points' residuals.
//
// A wall drawn with two lines (its two faces) is removed or moved as a whole, but the detector sees only
// the face towards the sensor; the other face (a parallel segment within twin_max_gap_m overlapping it)
// gets the same weight, or the points of the moved face would match the hidden one a few cm away.
#pragma once
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::matcher {

enum class DiffVerdict : int { kMissing = 1, kMoved = 2 };

struct FlaggedElement {
  int id = -1;  // plan element id
  DiffVerdict verdict = DiffVerdict::kMissing;
};

struct DiffWeightOptions {
  float missing_weight = 0;       // weight of an element marked missing (0: left out)
  float moved_weight = 0;         // ... marked moved
  bool twins = true;              // the other face of a two-line wall gets the same weight
  double twin_max_gap_m = 0.4;    // wall thickness up to this
};

// The other face of each segment (-1 if none): the nearest parallel segment (directions within ~3 deg)
// 2 cm .. twin_max_gap_m away whose overlap along the wall is at least half the shorter of the two.
std::vector<int> wall_twins(const FloorPlan& plan, double twin_max_gap_m = 0.4);

// Weights for every plan element (1 unless flagged); ids outside the plan are ignored.
std::vector<float> element_weights(const FloorPlan& plan, const std::vector<FlaggedElement>& flagged,
                                   const DiffWeightOptions& o = {});

// Holder for a node: the weights the look-ups read (stable address), updated from each diff.
class ElementWeights {
 public:
  ElementWeights(const FloorPlan& plan, DiffWeightOptions o);
  // Recomputes the weights; true when they changed.
  bool update(const std::vector<FlaggedElement>& flagged);
  const std::vector<float>* weights() const { return &w_; }
  int flagged() const { return flagged_; }  // elements (with twins) below weight 1

 private:
  const FloorPlan& plan_;
  DiffWeightOptions o_;
  std::vector<int> twins_;
  std::vector<float> w_;
  int flagged_ = 0;
};

}  // namespace fploc::matcher
