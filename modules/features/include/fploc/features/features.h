// LOAM-style wall features (paper section IV-B): smoothness along each ring of the wall points, corner and
// surface features with LOAM's neighbour/occlusion rules and per-sector limits, roll/pitch compensation,
// projection to the horizontal plane, and PCA line groups of surface points between corner anchors.
// Transport-free; nodes/features wraps it.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fploc/core/feature_frame.h"
#include "fploc/segmentation/segmenter.h"

namespace fploc::feat {

struct FeatureConfig {
  // Per-ring limits for a 64-ring sensor; with H rings, every round(H/64)-th ring is used (H > 64) or the
  // limits are multiplied by 64/H (H < 64), so a scan gives about as many features whatever the beam count.
  int sectors = 6;                  // per-ring sectors for the feature limits
  int max_corners_per_sector = 2;
  int max_surfaces_per_sector = 12;
  double corner_threshold = 0.002;  // smoothness c (dimensionless, src/smoothness.h) above which a point is a corner
  double surface_threshold = 0.0005;// smoothness below which a point is a surface point
  double max_range_m = 60.0;
  double min_range_m = 0.5;
  int half_window = 5;              // neighbours each side for the smoothness (LOAM: 5)
  int max_column_gap = 1;           // a larger column step breaks the neighbourhood (uneven spacing fakes curvature)
  double occlusion_ratio = 0.1;     // |r_i - r_j| > ratio * r_i between neighbours = occlusion boundary
  double parallel_ratio = 0.02;     // both-side range jumps > ratio * r_i = surface parallel to the beam
  int surface_spacing = 2;          // picked surface points suppress +-this many neighbours
  // A plan's wall stands from floor to ceiling, so at one azimuth nothing is seen beyond it: a wall point more than
  // column_front_m + column_front_ratio * range nearer (horizontally) than the farthest vertical structure seen in
  // its column (the column's second-farthest wall point, so two points at least) stands in front of a surface that
  // shows above or below it -- a cabinet, a table, a person -- and is never a feature. 0 = off (the default: 0.2 m
  // took corridor shelves s1 / s2 / s3 from 51.3 / 24.8 / 36.7 cm to 21.9 / 16.7 / 9.1 cm, but corridor s3 renovated
  // from 7.8 cm to 7.3 m; docs/notes/realism.md, thirty-third round).
  double column_front_m = 0;
  double column_front_ratio = 0.02;
  // Height as evidence (docs/notes/realism.md, fortieth round): a wall point at least high_band_m above the floor
  // (the segmenter's sensor height z plus the point's levelled z) stands above furniture, people and cabinets, so it
  // lies on a floor-to-ceiling wall or partition; a point below it may lie on anything. When a frame has at least
  // high_min_points such high wall points (and its z is known), a low point is no feature unless its column holds a
  // high point within high_same_surface_m of its levelled horizontal range (the same vertical surface); with
  // high_same_surface_m = 0 no low point is. With high_keep_unseen a low point whose column holds no high point at all
  // (a wall within ~3 m, whose upper part is above the beams) stays too: only high evidence against a point removes
  // it. 0 = off (the default: at 2.2 m, same surface 0.15 m, the shelved corridors
  // 4.7 / 11.8 / 18.9 -> 0.7 / 0.9 / 0.7 cm, but corridor s1 mixed 3 false-OK poses; with high_min_points 500 none, but
  // LOST on s3 renovated and the crowd's POOR x3; docs/notes/realism.md, fortieth round).
  double high_band_m = 0;
  int high_min_points = 200;
  double high_same_surface_m = 0;
  bool high_keep_unseen = false;
  // PCA line groups.
  int min_group_points = 4;
  double line_max_rms_m = 0.03;     // sqrt(smallest eigenvalue) of the group's 2D covariance
  double line_min_ratio = 20.0;     // largest / smallest eigenvalue
  double group_max_gap_m = 1.0;     // consecutive surface points farther apart end a run
};

class FeatureExtractor {
 public:
  explicit FeatureExtractor(FeatureConfig cfg = {});
  // Uses seg.wall (ring-major, increasing column per ring) and seg.roll/pitch. Status kBadInput when the
  // segmentation itself is BAD_INPUT/EMPTY (passed on), or its wall arrays disagree in size, or roll/pitch
  // are not finite; kFewFeatures below 30 features. Non-finite points are not in the frame.
  const FeatureFrame& process(const seg::Segmentation& seg);
  // Index of each feature of the last frame in the input wall points (diagnostics, bench).
  const std::vector<int32_t>& source() const { return source_; }
  const FeatureConfig& config() const { return cfg_; }

 private:
  enum Kind : int8_t { kCorner = int8_t(FeatureKind::kCorner), kSurface = int8_t(FeatureKind::kSurface) };
  // The features as they are picked, ring by ring (structure of arrays): the first n entries of the arrays (they
  // keep their size from scan to scan: entries written as picked, not constructed first).
  struct Picked {
    size_t n = 0;
    std::vector<float> x, y;          // gravity-aligned, sensor-centred [m]
    std::vector<int8_t> kind;
    std::vector<int32_t> group;       // -1 = unclassified
    std::vector<float> t;             // measurement time - utime [s] (from the wall points)
    std::vector<int32_t> source;      // index in the wall points
    int32_t num_groups = 0;
  };
  FeatureStatus extract(const seg::Segmentation& seg);
  void ring(const seg::Segmentation& seg, size_t begin, size_t end);
  static constexpr int kRefRings = 64;  // the sensor the per-ring limits are stated for (OS-1-64)
  FeatureConfig cfg_;
  int ring_step_ = 1;        // rings used: every ring_step_-th (from the beam count)
  double limit_scale_ = 1.0; // per-sector limits times this (from the beam count)
  Picked out_;
  FeatureFrame frame_;
  std::vector<int32_t> source_;
  Eigen::Matrix3f R_ = Eigen::Matrix3f::Identity();
  // Per-ring buffers, kept from scan to scan (src/smoothness.h).
  std::vector<float> corner_c_;               // c of corner candidates, -inf otherwise
  std::vector<uint64_t> surface_;             // bit i: point i is a surface candidate
  std::vector<float> surface_c_;              // c of the surface candidates
  std::vector<uint64_t> surf_keys_;           // a sector's surface candidates: (c, index) as sort keys
  std::vector<uint8_t> picked_;                  // suppressed by a pick or an occlusion boundary
  std::vector<uint64_t> pick_bits_;              // the ring's picks (features, corners) as bits
  std::vector<int> occ_, surf_, sel_, run_;
  std::vector<float> ring_w_;
  std::vector<float> far1_, far2_;            // per column: the farthest and second-farthest levelled range
  std::vector<float> level_range_;            // per wall point: its levelled horizontal range (column_front_m only)
  std::vector<uint8_t> low_;                  // per wall point: below the high band and not on a high surface
  std::vector<float> near_high_;              // per column: the nearest high point's levelled range
  std::vector<uint64_t> ring_brk_;
};

}  // namespace fploc::feat
