// pose_t <-> poses (6-DoF, covariance x y z roll pitch yaw). Pure mappings.
#pragma once
#include <fploc/pose_t.hpp>

#include <Eigen/Core>
#include <optional>
#include <string>

#include "fploc/core/pose.h"
#include "fploc/optimizer/window.h"

namespace fploc::adapters {

// From (x, y, yaw) + (roll, pitch, z): the 3x3 (x, y, yaw) covariance is placed in the 6x6, z and
// roll/pitch get the given sigmas. floor_index / floor: the floor the pose is on (index in the building's
// floor list, -1 unknown; a single plan is floor 0 named "0"), z the height above that floor's floor.
pose_t make_pose_msg(int64_t utime, int64_t seq, const Pose2& p, double roll, double pitch, double z,
                     const Eigen::Matrix3d& cov_xy_yaw, double z_sigma, double rp_sigma, int8_t status,
                     bool keyframe, bool final_estimate, int floor_index, const std::string& floor);
// A localized pose (it carries its own z and roll/pitch sigmas) on the given floor.
pose_t to_msg(const optimizer::PoseOut& p, int64_t seq, int floor_index, const std::string& floor);
// Pose2 from a pose_t (yaw of its quaternion; a zero quaternion is the identity).
Pose2 pose2_of(const pose_t& m);
// pose2_of when the pose is finite, else nullopt (the caller names the channel and drops it).
std::optional<Pose2> finite_pose2_of(const pose_t& m);
// The (x, y, yaw) block of a pose_t's 6x6 covariance (indices 0, 1, 5).
Eigen::Matrix3d xy_yaw_covariance(const pose_t& m);

}  // namespace fploc::adapters
