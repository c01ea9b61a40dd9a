// The floor-plan terms of one frame, shared by single-frame registration (matcher) and windowed
// optimisation (optimizer). Includes Ceres: include only from .cpp files of the localization libraries.
//
// For a pose estimate x, every feature point gets a short list of candidate targets from the look-up at
// its transformed position (gated by distance); points of one PCA group share the one element that fits
// the whole group best (the paper's rule). The residual of a point is p' - q(p'), q the closest point on
// the closest of its candidates, re-evaluated at every Ceres evaluation (so the correspondence slides
// along the element and can switch between the stored candidates). An outer loop re-runs the look-up.
#pragma once
#include <ceres/ceres.h>

#include <memory>
#include <string>
#include <vector>

#include "fploc/matcher/as_built.h"
#include "fploc/matcher/assignment.h"
#include "fploc/matcher/lookup.h"
#include "fploc/matcher/types.h"

namespace fploc::matcher {

// The points assign() uses at pose x: every o.stride-th, and with o.element_quota (element look-ups, stride > 1)
// also every point whose closest candidate within o.gate_m is an element holding at most element_quota of the
// frame's points, at sampling weight 1/sqrt(stride) (AssignOptions::element_quota). In point order.
void select_points(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, const AssignOptions& o,
                   std::vector<SampledPoint>* out);
// Whether select_points does more than take every o.stride-th point (the per-element budget or the askew rule,
// both needing element look-ups): callers that keep a selection compute one only then.
inline bool selects_per_element(const NearestLookup& lookup, const AssignOptions& o) {
  return ((o.element_quota > 0 && o.stride > 1) || o.askew_max_m > 0) && lookup.element_targets();
}

// Correspondences of the frame's points at pose x (in point order): of o.points when given, else of the
// points select_points chooses at x.
void assign(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, const AssignOptions& o,
            std::vector<Assignment>* out);

// Closest point on the closest of the candidates (lookup.geometry() ids) with the Jacobian d(p - q)/dp
// (normal projection for interior points of segments/circles/arcs, identity at end points and point
// targets); returns the distance.
double closest_of(const std::vector<TargetGeom>& targets, const int* cand, int n, const Eigen::Vector2d& p,
                  Eigen::Vector2d* q, Eigen::Matrix2d* dr_dp);

// The frame's terms as ONE residual block (2 residuals per assignment) with the robust loss ("huber",
// "cauchy", "none", scale [m]) folded exactly into the residuals: much less Ceres overhead than a block
// per point. Used by the matcher and the optimizer. The cost is weight^2 sum rho(|r|^2).
// compact: the same cost, gradient and Gauss-Newton matrix in 4 residuals (square-root information form,
// see FrameCost::evaluate_compact): the solver's steps are the same, without Ceres' per-row work.
// as_built (on): the as-built model above, always in the compact form.
void add_frame_term(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& a, const std::string& loss, double scale, double weight = 1.0,
                    bool compact = false, const AsBuiltModel* as_built = nullptr);

// The same term as a cost function of its own (one 3-parameter block: the pose), prepared at `pose` (the
// as-built model's robust weights and the walls' moments are fixed there), for a caller that keeps it across
// solves while the assignment holds (the optimizer's keys) and adds it to problems that do not take ownership
// (ceres::Problem::Options::cost_function_ownership = DO_NOT_TAKE_OWNERSHIP). Null when `a` is empty. The
// term refers to lookup.geometry(): the lookup must outlive it.
std::shared_ptr<ceres::CostFunction> make_frame_term(const double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                                                     const std::vector<Assignment>& a, const std::string& loss,
                                                     double scale, double weight = 1.0, bool compact = false,
                                                     const AsBuiltModel* as_built = nullptr);

// Gauss-Newton information J^T J of the frame term at x (robust weights included), for the covariance.
Eigen::Matrix3d frame_information(const NearestLookup& lookup, const FeatureFrame& f, const std::vector<Assignment>& a,
                                  const Pose2& x, const std::string& loss, double scale);

// Inlier ratio and rms against the nearest candidate at pose x (no gating other than inlier_m), over
// every stride-th point.
FitQuality evaluate_fit(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, double inlier_m,
                        int stride = 1);

}  // namespace fploc::matcher