// Trajectory accuracy as in Sturm et al., "A Benchmark for the Evaluation of RGB-D SLAM Systems"
// (IROS 2012) and the TUM tools (associate.py, evaluate_ate.py, evaluate_rpe.py):
//  - association: pairs (gt, est) whose time stamps differ by at most max_dt, greedily by smallest
//    difference, each pose used once;
//  - ATE: translational error |trans(Q_i^-1 S P_i)| after an optional rigid alignment S (none, SE(2)
//    about z, SE(3) by Horn/Umeyama without scale). fploc estimates live in the floor-plan frame, so
//    the default is no alignment;
//  - RPE: E_i = (Q_i^-1 Q_{i+D})^-1 (P_i^-1 P_{i+D}) over a time delta D (1 s default) or a frame count.
#pragma once
#include <Eigen/Geometry>
#include <string>
#include <utility>
#include <vector>

#include "fploc/core/pose.h"

namespace fploc::eval {

enum class Align { None, SE2, SE3 };
// "none", "se2", "se3"; throws std::invalid_argument otherwise.
Align parse_align(const std::string& s);

using Pairs = std::vector<std::pair<size_t, size_t>>;  // (gt index, est index), sorted by est time
// est time + offset is compared to gt time.
Pairs associate(const Trajectory& gt, const Trajectory& est, double max_dt = 0.02, double offset = 0.0);

struct Stats {
  size_t n = 0;
  double rmse = 0, mean = 0, median = 0, min = 0, max = 0, stddev = 0;
};
Stats summarize(std::vector<double> v);

// Rigid transform S with gt ≈ S * est over the paired positions (identity for Align::None or < 2 pairs
// for SE(2), < 3 for SE(3)).
Eigen::Isometry3d align(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, Align mode);

struct Ate {
  Stats trans;                 // metres
  Stats trans_xy;              // metres, horizontal (x, y) only: what a floor plan constrains
  Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
  std::vector<double> errors;  // per pair
};
Ate ate(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, Align mode = Align::None);

struct Rpe {
  Stats trans;    // metres per delta
  Stats rot_deg;  // degrees per delta
};
// delta in seconds (frames = false) or in associated poses (frames = true). For a time delta, the
// partner of pair k is the pair whose gt time is closest to t_k + delta (skipped when that is k itself
// or further than max_gap_s away from the requested time).
Rpe rpe(const Trajectory& gt, const Trajectory& est, const Pairs& pairs, double delta = 1.0, bool frames = false,
        double max_gap_s = 0.05);

// What a trajectory plot shows besides the two trajectories.
struct PlotOptions {
  // The floor plan as polylines (plan frame, metres), drawn under the trajectories.
  std::vector<std::vector<Eigen::Vector2d>> plan;
  std::string plan_label = "floor plan";  // its legend entry (e.g. which floor of a building is drawn)
  // Per estimate pose (same order as `est`), its error [m]; NaN = not associated. Non-empty: the
  // estimate is coloured by error (as evo's --plot_mode xy with colour mapping) with a colour bar.
  std::vector<double> est_error;
  // The axes frame the trajectories and the whole plan (false), or the trajectories only, with a margin of
  // frame_margin_m (true: a map with stray specks far from the building, or a campus plan around one corridor);
  // the plan is clipped to the axes either way.
  bool frame_trajectories = false;
  double frame_margin_m = 3.0;
};

// SVG (x-y plane, metres, equal axes, ticks and axis labels in metres, legend) of the ground truth and
// the (aligned) estimate, with the plan and the error colouring of `o`.
std::string plot_svg(const Trajectory& gt, const Trajectory& est, const std::string& title,
                     const Eigen::Isometry3d& S = Eigen::Isometry3d::Identity(), const PlotOptions& o = {});
// Per estimate pose, the translational error after S (|gt - S est| of its pair), NaN without a pair.
std::vector<double> pose_errors(const Trajectory& gt, const Trajectory& est, const Pairs& pairs,
                                const Eigen::Isometry3d& S = Eigen::Isometry3d::Identity());

}  // namespace fploc::eval
