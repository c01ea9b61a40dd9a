// Derivation of BeamScaling (see beam_scaling.h).
#include "fploc/segmentation/beam_scaling.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "segmenter_constants.h"

namespace fploc::seg {

BeamScaling beam_scaling(const BeamIntrinsics& beams, int width, const SegmenterConfig& cfg) {
  BeamScaling s;
  const int H = beams.beams();
  if (H <= 0 || width <= 0) return s;
  s.pixel_scale = double(H) * double(width) / (double(k::kRefBeams) * double(k::kRefWidth));
  // Seed rings: the rings (from the top; the bottom ones for the ground use the same count) whose altitude
  // lies within the band the K_r reference rings cover, i.e. K_r reference ring spacings below the top
  // ring; at least kMinSeedRings (a sparse sensor's top ring alone is one azimuth line).
  std::vector<double> alt = beams.altitude_deg;
  std::sort(alt.begin(), alt.end(), std::greater<>());
  const int kr = std::max(1, cfg.seed_rings);
  const double band = (kr - 0.5) * k::kRefRingSpacingDeg;
  const auto in_band = [&](double top, auto first, auto last) {
    return int(std::count_if(first, last, [&](double a) { return std::abs(a - top) <= band; }));
  };
  const int top_n = in_band(alt.front(), alt.begin(), alt.begin() + H / 2);
  const int bottom_n = in_band(alt.back(), alt.rbegin(), alt.rbegin() + H / 2);
  s.seed_rings = std::clamp(std::max(top_n, bottom_n), std::min(k::kMinSeedRings, H / 2), std::max(1, H / 2));
  // Strides and the inlier count follow the number of returns.
  s.start_stride = std::max<size_t>(1, size_t(std::lround(double(k::kStartStride) * s.pixel_scale)));
  s.final_stride = std::max<size_t>(1, size_t(std::lround(double(k::kFinalStride) * s.pixel_scale)));
  s.min_plane_inliers = std::max(k::kMinPlaneInliersFloor, int(std::lround(cfg.min_plane_inliers * s.pixel_scale)));
  const int upper = H / 2;
  const int steep = int(std::count_if(alt.begin(), alt.begin() + upper, [](double a) { return a >= k::kRefSteepRingDeg; }));
  const double share = upper > 0 ? double(steep) / upper : 0.0;
  s.min_inlier_fraction = cfg.min_inlier_fraction * std::min(1.0, share / k::kRefSteepShare);
  return s;
}

}  // namespace fploc::seg
