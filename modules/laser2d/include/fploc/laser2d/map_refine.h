// Refining the poses a map is built from (the mapping part of `fploc bench real`, docs/notes/real2d.md, twenty-first
// pass). The Radish reference poses carry 2-5 cm of per-pose noise (three-cornered hat, sixteenth pass); a raster of
// the scans at those poses carries it as walls blurred and thickened by it, and every fit against that raster
// carries it too. Here each scan is aligned to the *other* scans, as a mapper's scan-to-map refinement would:
//
//  - leave-group-out: the scans k with k % groups == g are aligned to the points of all the other scans at their
//    current poses (a scan is never aligned to itself), group after group (Gauss-Seidel), for `passes` passes;
//  - point to line: a point's residual is its distance along the normal of the line fitted (PCA) to the others'
//    points in the (2 radius_cells + 1)^2 cells of cell_m around the point's cell, when those points are linear
//    (smallest / largest eigenvalue <= max_flatness): the others' *mean* wall, not their union, so the noise of the
//    others averages out (a distance field of the others' raster would be flat across the blurred band);
//    Huber loss, a few ICP rounds (associate, Ceres solve);
//  - a prior on the pose the scan started from (the reference) with sigma prior_*: where the others constrain a
//    direction the scans average their noise out, where they do not (along a corridor, a room seen once) the
//    reference holds it, and the map stays in the reference's frame;
//  - a refinement is taken only when at least min_inlier_ratio of the scan's points lie within inlier_m of an
//    accepted line and it stays within max_shift_m / max_turn_rad of the reference; otherwise the pose is kept.
// Used by `fploc import-carmen --refine-map-poses` / `fploc bench real --refine-map-poses` (off by default: on the five
// Radish logs it moved the floors by -0.4..+0.5 cm and the tracker's ATE both ways; docs/notes/real2d.md, twenty-first
// pass). Transport-free.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "fploc/core/pose.h"

namespace fploc::laser2d {

// kLines: point to the others' mean line (above). kField: the grid localizer's fit (field_fit.h) on the distance
// field of a raster of the others' hits: flat (zero) across their blurred band, so it pulls a scan into the band,
// not to its middle (measured for comparison, docs/notes/real2d.md).
enum class MapRefineMethod { kLines, kField };

struct MapRefineConfig {
  MapRefineMethod method = MapRefineMethod::kLines;
  int passes = 3;
  int groups = 4;
  double cell_m = 0.05;
  int normal_bins = 4;              // the others' points by their normal's orientation (>= 3)
  int radius_cells = 3;             // the line of a point: the others' points within +-radius_cells cells
  int min_line_points = 6;
  double max_flatness = 0.3;        // smallest / largest eigenvalue of those points' covariance
  double max_normal_angle_rad = 20.0 * M_PI / 180;  // and its normal within this of the scan's own at the point
  double point_sigma_m = 0.05, huber_m = 0.05;
  double prior_sigma_xy_m = 0.05, prior_sigma_yaw_rad = 1.0 * M_PI / 180;
  double inlier_m = 0.1;
  double min_inlier_ratio = 0.25;   // of the scan's points on an accepted line within inlier_m
  int min_inliers = 20;
  double max_shift_m = 0.2, max_turn_rad = 3.0 * M_PI / 180;
  int icp_rounds = 5;
  int max_iterations = 10;          // Ceres iterations per round
  int max_points = 400;             // per scan (every k-th)
  // After each pass the corrections' moving mean over +-highpass_scans scans is removed (0: off): the reference's
  // error is white per pose (sixteenth pass), so only the corrections' scan-to-scan part is applied.
  int highpass_scans = 0;
};

struct MapRefineStats {
  struct Pass {
    int refined = 0, kept = 0;        // scans moved / left at their pose (too few inliers, too far)
    double rms_shift_m = 0;           // of the taken refinements' shift in this pass
    double rms_from_start_m = 0;      // of every pose's offset from the starting (reference) pose after the pass
    double rms_from_start_yaw_rad = 0;
    double rms_residual_m = 0;        // of the inlier residuals at the taken poses
  };
  std::vector<Pass> passes;
};

// scans[k]: the points of scan k in its own (laser) frame; poses[k]: its starting (reference) pose. Returns the
// refined poses (same order).
std::vector<Pose2> refine_map_poses(const std::vector<std::vector<Eigen::Vector2d>>& scans, const std::vector<Pose2>& poses,
                                    const MapRefineConfig& cfg = {}, MapRefineStats* stats = nullptr);

}  // namespace fploc::laser2d
