// The segmenter's sensor-dependent numbers, derived from the beam pattern (issue 13 item 2) instead of
// OS-1-64 constants: the options (seed_rings, min_plane_inliers) and the fixed subsampling strides are
// stated for the paper's sensor (OS-1-64, 1024 columns, rings ~0.53 deg apart) and scaled here. For that
// sensor every value equals the option/constant itself, so its results do not change.
#pragma once
#include <cstddef>

#include "fploc/core/scan.h"
#include "fploc/segmentation/segmenter_config.h"

namespace fploc::seg {

struct BeamScaling {
  double pixel_scale = 1.0;   // (beams x columns) / (64 x 1024): how many more returns than the reference
  int seed_rings = 4;         // K_r: the top (bottom) rings within the elevation band the paper's K_r rings span
  size_t start_stride = 24;   // start scores on every start_stride-th candidate (~1.4k points)
  size_t final_stride = 3;    // refined-plane scores on every final_stride-th candidate (~11k points)
  int min_plane_inliers = 200;// inliers a plane needs (the option counts returns of the reference sensor)
  // Ceiling inliers needed as a fraction of the upper-ring returns: the option times the share of upper rings
  // steeper than the reference's median upper ring (8.3 deg) relative to the reference's (one half), at
  // most 1x. A sensor whose upper rings crowd the horizon (OS-1-32 "gradient") sees the ceiling with few.
  double min_inlier_fraction = 0.02;
};

// `beams` and `width` of the scan; cfg.seed_rings and cfg.min_plane_inliers are the reference values.
BeamScaling beam_scaling(const BeamIntrinsics& beams, int width, const SegmenterConfig& cfg);

}  // namespace fploc::seg
