// Options of the floor-plan terms' as-built model (plan_terms.h add_frame_term). No Ceres here: the
// matcher's and the optimizer's configs hold one.
#pragma once

namespace fploc::matcher {

// As-built walls: a building's walls stand a few cm from where the drawing puts them, each by its own
// offset, so the points of one wall share one error and a wall seen with many points (a near one) pulls
// the pose by its whole offset. With sigma_m > 0 every plan segment the frame's points lie on gets a
// nuisance offset along its normal at each of its ends, o_a and o_b (a point at fraction t of the segment
// is off by (1 - t) o_a + t o_b), with the prior o ~ N(0, sigma_m^2) under a Cauchy loss of scale
// loss_scale_m (a wall moved by decimetres pulls as little as an outlier point does), against the
// points' own noise point_sigma_m; the offsets are solved per evaluation (IRLS, closed form per segment)
// and eliminated (Schur complement): what is left is the GLS cost of the pose with per-wall correlated
// errors. A wall's pull saturates at about (point_sigma_m / sigma_m)^2 points, whatever its number of
// points: every wall in view counts about the same, none beyond its bounded share. Points on segment
// ends, circles and arcs stay plain. keep_information: the frame's term is scaled (once, at the pose it
// is built at) to the plain term's translational information, so its balance against the other terms
// (the matcher's prediction prior, the optimizer's velocity regularisation) stays what it was.
struct AsBuiltModel {
  double sigma_m = 0;           // 0: off (the paper's per-point terms)
  double point_sigma_m = 0.04;  // (point_sigma_m / sigma_m)^2 = 4 points per wall end at sigma_m 2 cm
  double loss_scale_m = 0.03;   // <= 0: no loss on the offsets (Gaussian prior)
  bool keep_information = true;
  // A wall's points that do not lie on one line with it are no wall standing off its drawn place (a cabinet's
  // face seen through a glass wall, behind it and askew): when their rms spread about the wall's fitted offsets
  // (weighted by the points' robust weights) exceeds max_spread_sigmas * point_sigma_m, the element's share (its
  // points' and its offsets' prior weights alike) is scaled by (max_spread_sigmas * point_sigma_m / spread)^2,
  // so it no longer pulls as a whole wall does. <= 0: off (the default: at 1 it takes the corridor glass world's
  // seed 2 from 5.25 to 1.96 cm but costs the as-built worlds at sigma 5 cm 1-8 %, docs/notes/realism.md).
  double max_spread_sigmas = 0;
  // The spread alone cannot tell a face or partition askew to its wall from a wall standing a few cm off its
  // drawn place (its points spread about the offsets the prior holds small too), and cutting real walls' shares
  // loses what holds a corridor. With max_askew_m > 0 the spread rule
  // applies only to an element whose points' own line (their end offsets by least squares, no prior) turns
  // against the wall: its offsets at the wall's two ends differ by more than about max_askew_m * sqrt(2),
  // counting that line's own uncertainty (the 99 % point of chi-square with 1 degree of freedom). A displaced
  // wall keeps its share; a cabinet's face 22 deg askew, whose line meets the wall's
  // ends metres apart, does not. 0: the spread rule applies to every element.
  double max_askew_m = 0;
  // Evaluate the points of a wall through the wall's moments (plan_terms.cpp aggregate_walls: one pass over
  // the walls per evaluation instead of a closest-point query per point; the same cost, gradient and
  // Gauss-Newton matrix at the pose the term is prepared at, the points' position along their wall held
  // there). false: every point at every evaluation.
  bool per_wall = true;
  bool on() const { return sigma_m > 0 && point_sigma_m > 0; }
};

}  // namespace fploc::matcher
