// ground_truth_t from the simulator's ground truth (pose, linear and angular velocity). Pure mapping.
#pragma once
#include <fploc/ground_truth_t.hpp>

#include <Eigen/Core>
#include <string>

#include "fploc/core/pose.h"

namespace fploc::adapters {

ground_truth_t ground_truth_msg(int64_t utime, int64_t seq, const StampedPose& p, const Eigen::Vector3d& v,
                                const Eigen::Vector3d& w, const std::string& scenario);

}  // namespace fploc::adapters
