// Global (re)localization against the floor plan: where on the plan does this scan fit, with no (or a
// lost) initial pose? The paper assumes a given initial pose; a robot that is switched on somewhere,
// or that lost track, needs this (AMCL's "global localization").
//
// A correlative search over (x, y, yaw): every cell of a grid over the plan's free space (the sensor is
// at least `clearance_m` from every element) × yaw steps is scored with a subsample of the scan's
// features, each point contributing max(0, 1 - (d / truncate)^2) for its distance d to the plan (one
// read of a distance grid). Hypotheses are pruned as soon as they cannot beat the current list of best
// ones. The best few *distinct* hypotheses are refined by single-frame registration (register_frame)
// and the result is accepted only when it fits well and is significantly better than every distinct
// alternative (a paired test on the features one explains and the other does not) — in self-similar
// corridors the answer is "ambiguous", never a confident jump.
// Transport-free; the matcher node uses it when it has no pose or is LOST.
#pragma once
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/matcher/lookup.h"
#include "fploc/matcher/matcher.h"
#include "fploc/matcher/types.h"

namespace fploc::annf {
class DistanceGrid;
}  // namespace fploc::annf

namespace fploc::reloc {

struct RelocalizerConfig {
  double grid_m = 0.5;            // translation step of the search
  double yaw_step_deg = 5.0;      // yaw step
  int max_points = 160;           // features scored per hypothesis (evenly spread over the scan)
  double truncate_m = 0.5;        // a point farther than this from the plan scores 0
  double clearance_m = 0.3;       // hypotheses are at least this far from every element
  double distance_cell_m = 0.1;   // resolution of the distance grid behind the scores
  int keep = 32;                  // best distinct places kept during the search
  int refine = 8;                 // best distinct hypotheses refined with register_frame
  double distinct_m = 1.0;        // hypotheses closer than this (and distinct_deg) are the same place
  double distinct_deg = 20.0;
  double min_inlier_ratio = 0.5;  // the refined best must explain this share of the features ...
  // ... and be significantly better than every distinct runner-up: McNemar's test on the points one
  // explains and the other does not, (b - c)^2 / (b + c) >= this (chi-square, 1 dof; 10.83 = p 0.001).
  double min_evidence = 10.83;
  double inlier_m = 0.1;          // a point within this of the plan is explained (for the test above)
  matcher::MatcherConfig registration;     // for the refinement
};

// Where to search: a disc around `center` (all yaws, or yaw within ± yaw_window of center.yaw).
struct SearchRegion {
  Pose2 center;
  double radius_m = 3.0;
  double yaw_window_rad = M_PI;   // >= pi: every yaw
};

struct RelocHypothesis {
  Pose2 pose;
  double score = 0;               // correlative score (0..points)
  matcher::FitQuality fit;                 // after refinement (num_points 0 when not refined)
  double evidence = 0;            // McNemar statistic against the best (0 for the best itself)
};

enum class RelocStatus : int8_t { kFound = 0, kAmbiguous = 1, kNoFit = 2 };
const char* to_string(RelocStatus s);

struct RelocResult {
  RelocStatus status = RelocStatus::kNoFit;
  Pose2 pose;                     // the accepted pose (kFound), else the best refined hypothesis
  matcher::FitQuality fit;
  std::vector<RelocHypothesis> candidates;  // refined, best first
  int64_t hypotheses = 0;         // (x, y, yaw) triples scored (fully or until pruned)
  int points = 0;                 // features used in the scores
  std::string text;               // why not found / how ambiguous
};

class Relocalizer {
 public:
  // `lookup` is the one the refinement registers with (the matcher's); the plan gives the distance grid.
  Relocalizer(const FloorPlan& plan, const matcher::NearestLookup& lookup, RelocalizerConfig cfg = {});
  ~Relocalizer();
  Relocalizer(const Relocalizer&) = delete;
  Relocalizer& operator=(const Relocalizer&) = delete;

  RelocResult locate(const FeatureFrame& f, const std::optional<SearchRegion>& region = std::nullopt) const;
  // Free-space cells the whole-plan search visits (for logs).
  size_t free_cells() const { return free_.size(); }
  const RelocalizerConfig& config() const { return cfg_; }

 private:
  // 1 for each test point (every stride-th feature) within inlier_m of the plan at `pose`.
  std::vector<uint8_t> explained_points(const FeatureFrame& f, const Pose2& pose, int stride) const;
  const matcher::NearestLookup& lookup_;
  RelocalizerConfig cfg_;
  std::unique_ptr<annf::DistanceGrid> grid_;
  std::vector<Eigen::Vector2d> free_;  // search cell centres with clearance
};

}  // namespace fploc::reloc