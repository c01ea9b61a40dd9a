// Honest covariance of one frame's floor-plan registration (issue 12, "honest uncertainty").
//
// The Gauss-Newton covariance sigma^2 H^-1 treats every feature point as an independent measurement of
// the pose: with hundreds of points it says sub-millimetre, while the plan itself is wrong by centimetres
// (walls a few cm from where the drawing puts them, a moved partition, a drawing scale error) and every
// point on one wall shares that wall's error. Measured: NEES 60-500 on perturbed worlds.
//
// Here the covariance is the sandwich (robust / cluster) form of the same M-estimate:
//   P = H^-1 M H^-1,  H = sum_i w_i j_i j_i^T,
//   M = sigma_s^2 sum_i w_i^2 j_i j_i^T + sum_e sigma_e^2 G_e G_e^T
// with j_i the point's residual gradient wrt (x, y, yaw), w_i its robust (IRLS) weight, sigma_s the point
// noise and, per plan element e, G_e the sensitivity of the weighted normal equations to the element's
// error: for a segment its two end points each displaced along the normal (the offset varies linearly
// along the wall: an offset plus a rotation), for a circle/arc/point target a translation in x and y.
// Both sigmas come from the frame's own residuals at the estimate (no constant tuned to one world):
//   sigma_s^2: the weighted spread of the residuals about their element's mean offset;
//   sigma_e^2: max(plan_sigma^2, the frame's pooled element-offset variance), or the element's own offset^2
//              where that is > 4x the pooled one (a moved wall), each offset^2 corrected for the noise of
//              its mean and for what the pose absorbed (G/(G-3)).
// Rotation-translation coupling is in j_i (the yaw column is the lever arm). Directions that no point
// constrains (a corridor's axis) get `max_variance` instead of an inverse of zero.
#pragma once
#include <Eigen/Core>
#include <string>

#include "fploc/matcher/lookup.h"
#include "fploc/matcher/types.h"

namespace fploc::optimizer {

struct CovarianceConfig {
  double plan_sigma_m = 0.0;          // floor on each element end's offset sigma (the drawing's own accuracy)
  double min_noise_sigma_m = 0.002;   // floor on the point noise sigma
  bool element_correlation = true;    // false: points independent (sigma_s^2 H^-1 with the observed sigma_s)
  // Each element's sigma_e^2: "model" = the pooled one, except an element whose own offset^2 is > 4x the
  // pooled (a moved wall) keeps its own; "model-max" = max(pooled, own) per element (more conservative).
  // (The cluster-robust meat, sum_e u_e u_e^T of the observed scores, was measured overconfident: mean
  // NEES 9-59 in covariance_test's Monte Carlo, too few elements per direction.)
  std::string estimator = "model";
  bool two_ends = true;               // segment error = its two ends' normal offsets (else one offset)
  bool robust_noise = true;           // noise meat from each point's own score (else sigma_s^2 w^2)
  bool median_pooling = true;         // pooled element variance = median / 0.455 (else the mean)
  double gate_m = 0.3;                // correspondence gate around the pose
  bool group_rule = true;
  int max_points = 800;               // every k-th point to keep about this many (0: all)
  std::string loss = "cauchy";        // the estimator's robust loss ("cauchy", "huber", "none") ...
  double loss_scale_m = 0.05;         // ... and its scale: the weights w_i
  double max_variance = 1e4;          // variance [m^2, rad^2] of a direction nothing constrains
  // The estimator's as-built model (matcher/as_built.h) with its Cauchy loss of this scale on the elements'
  // offsets (0: no such model): an element far off the others (a moved wall, "model" keeps its own offset) then
  // pulls the pose by its offset's influence o w(o), w = 1 / (1 + o^2 / c^2), not by its whole offset; its
  // sigma_e is scaled by w (never below the pooled one).
  double element_loss_scale_m = 0;
};

struct FrameUncertainty {
  bool valid = false;                 // enough correspondences for a covariance
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity() * 1e4;  // x, y, yaw
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();           // H (robust-weighted J^T J, unit noise)
  double noise_sigma_m = 0;           // sigma_s
  double element_sigma_m = 0;         // the frame's pooled element-end sigma (before the plan_sigma floor)
  int points = 0;                     // correspondences used
  int elements = 0;                   // plan elements they fall on
};

// The covariance of the pose x of frame f (de-skewed to the pose's time) registered against the plan.
FrameUncertainty frame_uncertainty(const matcher::NearestLookup& lookup, const FeatureFrame& f, const Pose2& x,
                                   const CovarianceConfig& cfg);

// IRLS weight rho'(r^2) of the loss ("cauchy", "huber", "none"; other names: cauchy) at residual r.
double robust_weight(const std::string& loss, double scale, double r);

}  // namespace fploc::optimizer
