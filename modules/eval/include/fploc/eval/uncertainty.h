// Honest uncertainty (issue 12): does the published covariance mean something?
//  - NEES (normalised estimation error squared) of x, y, yaw against ground truth: e^T P^-1 e with
//    e = (gt - est) in x, y and the wrapped yaw difference, P the pose's x/y/yaw covariance. For a
//    consistent estimator its mean is the degrees of freedom (3; 1 per single component).
//  - false OK: poses whose status is OK while their horizontal error exceeds a threshold (0.3 m).
// The uncertainty file (written by fploc-pose-logger's uncertainty_file) holds one line per pose:
//   t status xx xy xyaw yy yyaw yawyaw     (status 0 OK, 1 POOR, 2 LOST; covariance of x, y, yaw)
// with '#' comments; its times are the TUM file's.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/eval/eval.h"

namespace fploc::eval {

struct PoseUncertainty {
  double t = 0;
  int status = 0;  // 0 OK, 1 POOR, 2 LOST
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // x, y, yaw
};

// One line of the uncertainty file (fixed formatting, so files are reproducible).
std::string uncertainty_line(const PoseUncertainty& u);
// Throws std::runtime_error naming the file and line of a bad record.
std::vector<PoseUncertainty> read_uncertainty(const std::string& path);

struct Consistency {
  size_t poses = 0;          // associated poses with an uncertainty record
  size_t nees_poses = 0;     // of those, with a positive definite covariance
  Stats nees;                // 3-DoF NEES (x, y, yaw)
  Stats nees_x, nees_y, nees_yaw;  // 1-DoF NEES of each component
  size_t ok = 0;             // status OK
  size_t false_ok = 0;       // status OK and horizontal error > false_ok_m
  double false_ok_share = 0; // false_ok / poses
  double false_ok_m = 0.3;
};

// Pairs as from associate(gt, est); the uncertainty record of est pose j is the one at its time (within
// max_dt). S aligns the estimate (identity: both in the plan frame).
Consistency consistency(const Trajectory& gt, const Trajectory& est, const Pairs& pairs,
                        const std::vector<PoseUncertainty>& u, double false_ok_m = 0.3,
                        const Eigen::Isometry3d& S = Eigen::Isometry3d::Identity(), double max_dt = 1e-4);

}  // namespace fploc::eval
