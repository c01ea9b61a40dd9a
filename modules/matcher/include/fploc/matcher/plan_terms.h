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

#include "fploc/matcher/lookup.h"
#include "fploc/matcher/types.h"

namespace fploc {

constexpr int kMaxCandidates = 8;

struct Assignment {
  int point = -1;
  int n = 0;
  int cand[kMaxCandidates] = {};
};

struct AssignOptions {
  double gate_m = 1.0;     // points farther than this from all candidates are left out
  bool group_rule = true;  // one PCA group <-> one element (element look-ups only)
  int max_candidates = kMaxCandidates;
  int stride = 1;          // use every stride-th point (1 = all)
};

// Correspondences of the frame's points at pose x.
void assign(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, const AssignOptions& o,
            std::vector<Assignment>* out);

// Closest point on the closest of the candidates, with the Jacobian d(p - q)/dp (normal projection
// for interior points of segments/circles/arcs, identity at end points and point targets).
double closest_of(const std::vector<Element>& targets, const int* cand, int n, const Eigen::Vector2d& p,
                  Eigen::Vector2d* q, Eigen::Matrix2d* dr_dp);

// One point's residual (2 values) on a pose block {x, y, yaw}.
ceres::CostFunction* make_point_cost(const std::vector<Element>* targets, const Assignment& a,
                                     const Eigen::Vector2d& p_sensor, double weight);

// Adds one residual block per assignment to the problem. `loss` is not owned by the problem (create the
// problem with loss_function_ownership = DO_NOT_TAKE_OWNERSHIP).
void add_plan_terms(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& a, ceres::LossFunction* loss, double weight = 1.0);

// Robust loss by name ("huber", "cauchy", "none" = nullptr) with scale [m].
std::unique_ptr<ceres::LossFunction> make_loss(const std::string& name, double scale);

// The same terms as ONE residual block for the whole frame (2 residuals per assignment) with the robust
// loss ("huber", "cauchy", "none", scale [m]) folded exactly into the residuals: much less Ceres
// overhead than a block per point. Used by the matcher and the optimizer.
void add_frame_term(ceres::Problem* problem, double* pose, const NearestLookup& lookup, const FeatureFrame& f,
                    const std::vector<Assignment>& a, const std::string& loss, double scale, double weight = 1.0);

// Inlier ratio and rms against the nearest candidate at pose x (no gating other than inlier_m).
FitQuality evaluate_fit(const NearestLookup& lookup, const FeatureFrame& f, const Pose2& x, double inlier_m);

}  // namespace fploc
