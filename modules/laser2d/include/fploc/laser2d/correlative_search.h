// Branch-and-bound correlative scan matching on a DistanceField (Olson's correlative search, made exact and
// fast as in Cartographer's fast correlative scan matcher, Hess et al. 2016): the score of a pose is the mean
// over the scan's points of exp(-d^2 / 2 s^2) (d from the distance field at the point's cell), times a prior
// exp(-m^2 / 2 kappa^2) on the Mahalanobis offset m from the window's centre. The search visits every yaw step
// of the window and, per yaw, the cell offsets through precomputed max-pooled score grids (level h: the max
// over 2^h x 2^h cells, quantised upwards to 8 bits), pruning every block whose upper bound cannot beat the
// candidates kept. The best candidate is the exhaustive search's best (the bounds are exact upper bounds);
// the K best *distinct* candidates (apart by more than sep_xy or sep_yaw) are kept for refinement and for
// re-acquisition hypotheses. Transport-free.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/floorplan/distance_field.h"

namespace fploc::laser2d {

// The per-cell score exp(-d^2 / 2 s^2) and its max-pooled pyramid, built once per map.
class ScorePyramid {
 public:
  ScorePyramid(const DistanceField& df, double score_sigma_m, int levels = 8);
  int levels() const { return int(pooled_.size()) + 1; }
  int width() const { return w_; }
  int height() const { return h_; }
  // Level 0: exact score (0 off the map).
  float score(int i, int j) const {
    return (i < 0 || j < 0 || i >= w_ || j >= h_) ? 0.f : s_[size_t(j) * size_t(w_) + size_t(i)];
  }
  // Level h >= 1: an upper bound (8-bit, /255) of the max over cells [i, i + 2^h) x [j, j + 2^h).
  int bound(int h, int i, int j) const {
    const int w = 1 << h;
    if (i <= -w || j <= -w || i >= w_ || j >= h_) return 0;
    return pooled_[size_t(h - 1)][size_t(std::max(j, 0)) * size_t(w_) + size_t(std::max(i, 0))];
  }

 private:
  int w_ = 0, h_ = 0;
  std::vector<float> s_;
  std::vector<std::vector<uint8_t>> pooled_;
};

struct SearchWindow {
  Pose2 center;                       // the prediction
  double xy_m = 0.5, yaw_rad = 0.2;   // searched: +-xy_m (both axes), +-yaw_rad
  double yaw_step_rad = M_PI / 180;
  double sigma_xy_m = 0.3, sigma_yaw_rad = 0.1;  // the prior's sigmas (Mahalanobis offset)
  double prior_kappa = 1.5;           // prior exp(-m^2 / 2 kappa^2); <= 0: no prior
};

struct SearchCandidate {
  Pose2 pose;
  double score = 0;  // prior-weighted mean score
  double fit = 0;    // mean score without the prior
};

struct SearchOptions {
  int keep = 1;                    // distinct candidates returned (best first)
  double sep_xy_m = 0.3, sep_yaw_rad = 10 * M_PI / 180;  // distinct: farther apart than either
  double min_ratio = 0.0;          // prune blocks whose bound < min_ratio * best (0: only the K-th best prunes)
  double min_score = 0.0;          // prune blocks whose bound < this (candidates below it are of no use)
  // Where a candidate may stand (e.g. a known-free cell of the map, for a search over the whole map); empty: anywhere.
  // Asked of each leaf that would be kept (its position in world coordinates).
  std::function<bool(double x, double y)> position_ok;
};

struct SearchStats {
  long leaves = 0, nodes = 0;
};

// points: the scan in the robot frame (at most a few hundred). Candidates sorted by score, best first.
std::vector<SearchCandidate> correlative_search(const DistanceField& df, const ScorePyramid& pyr,
                                                const std::vector<Eigen::Vector2d>& points, const SearchWindow& win,
                                                const SearchOptions& opt, SearchStats* stats = nullptr);

// The exhaustive search over the same window (reference for the tests; the best candidate only).
SearchCandidate correlative_search_exhaustive(const DistanceField& df, const ScorePyramid& pyr,
                                              const std::vector<Eigen::Vector2d>& points, const SearchWindow& win);

}  // namespace fploc::laser2d
