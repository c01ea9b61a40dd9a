// How noisy is the reference itself? The three-cornered hat (Grubbs 1948; Gray & Allan 1974, used for clocks):
// three independent measurements A, B, C of the same quantities, with errors of variances a, b, c, give
//   var(A - B) = a + b,  var(A - C) = a + c,  var(B - C) = b + c,
// three equations for the three variances, without knowing the truth. Here the quantities are a trajectory's
// increments (x, y in the previous pose's frame, and yaw) between consecutive reference poses, and the three
// are the reference, an estimate and a third trajectory (e.g. wheel odometry), associated by time.
//
// Used on the Radish logs, whose reference (the "corrected" laser poses of the logs' authors) is itself a
// scan-matching result: against a reference with per-pose noise of sigma, even a perfect localizer scores an ATE
// of about sigma. Assumptions (say them with the figures): the three errors are uncorrelated (an estimate made
// from the same scans as the reference shares some of its error, which makes the reference look *less* noisy);
// the per-pose noise is white, so an increment's variance is twice a pose's (check it with lag > 1: white
// noise gives the same increment variance at every lag, a drift a growing one). A negative variance means
// the assumptions fail (or too few increments); it is reported as is, not clipped. An estimate within the rounding
// of its sums (|v| <= 1e-12 of the mean square of the differences: e.g. a constant difference) is 0. NaN: the
// differences overflow a double (coordinates of 1e200).
#pragma once
#include <string>

#include "fploc/core/pose.h"

namespace fploc::eval {

struct HatSource {
  double increment_var_xy_m2 = 0;    // variance of the increment's x + y errors (sum over the two axes)
  double increment_var_yaw_rad2 = 0;
  // Per pose, if the noise is white: increment variance / 2 (horizontal: x and y together), signed sqrt.
  double pose_sigma_xy_m = 0;
  double pose_sigma_yaw_rad = 0;
};

struct HatResult {
  size_t increments = 0;  // increments where all three trajectories have both poses
  HatSource ref, est, third;
};

// Increments between reference poses `lag` apart (in index), each of est and third associated to the
// reference pose by time (within max_dt; est_offset is added to est's times, as eval's --offset). An increment
// counts only where both trajectories have both of its poses (drop an estimate's unreliable poses to leave them
// out). Throws std::invalid_argument with fewer than 3 increments.
HatResult three_cornered_hat(const Trajectory& ref, const Trajectory& est, const Trajectory& third, double max_dt = 0.02,
                             int lag = 1, double est_offset = 0);

// sign(v) * sqrt(|v|): a standard deviation that keeps a negative variance visible.
double signed_sqrt(double v);

}  // namespace fploc::eval
