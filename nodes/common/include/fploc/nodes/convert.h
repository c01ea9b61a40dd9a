// Conversions between the transport-free core types and their LCM messages (shared by all nodes).
#pragma once
#include <fploc/ground_truth_t.hpp>
#include <fploc/imu_t.hpp>
#include <fploc/scan_t.hpp>

#include <Eigen/Core>
#include <string>

#include "fploc/core/pose.h"
#include "fploc/core/scan.h"

namespace fploc {

void to_msg(const Scan& s, scan_t& m);
// Throws std::runtime_error naming the field when the message is inconsistent (sizes, beam count).
void from_msg(const scan_t& m, Scan& s);

// Simulator ground truth: pose, linear and angular velocity at `utime`.
ground_truth_t ground_truth_msg(int64_t utime, int64_t seq, const StampedPose& p, const Eigen::Vector3d& v,
                                const Eigen::Vector3d& w, const std::string& scenario);

}  // namespace fploc
