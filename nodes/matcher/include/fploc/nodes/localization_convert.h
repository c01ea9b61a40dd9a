// LCM <-> localization types (features_t -> FeatureFrame, results -> frame_pose_t / pose_t), shared by
// the matcher, optimizer and odometry nodes.
#pragma once
#include <fploc/features_t.hpp>
#include <fploc/frame_pose_t.hpp>
#include <fploc/pose_t.hpp>

#include <Eigen/Core>
#include <string>

#include "fploc/localizer/localizer.h"
#include "fploc/matcher/map.h"
#include "fploc/matcher/types.h"
#include "options/common.pb.h"

namespace fploc::rt {
class Context;
}

namespace fploc {

// Non-finite points are dropped (counted in *dropped). Throws std::runtime_error naming the field when
// the arrays disagree with num_points.
FeatureFrame from_msg(const features_t& m, int* dropped = nullptr);

// 6-DoF pose message from (x, y, yaw) + (roll, pitch, z); covariance: the 3x3 (x, y, yaw) block is
// placed in the 6x6 (x y z roll pitch yaw), z/roll/pitch get the given sigmas.
pose_t make_pose_msg(int64_t utime, int64_t seq, const Pose2& p, double roll, double pitch, double z,
                     const Eigen::Matrix3d& cov_xy_yaw, double z_sigma, double rp_sigma, int8_t status,
                     bool keyframe, bool final_estimate);

// A localized pose (with its own z and roll/pitch sigmas) as a pose_t.
pose_t to_msg(const localizer::Pose& p, int64_t seq);

// The SFR step's result as the optimizer reads it from a frame_pose_t: a non-finite twist is zero, an
// unknown status LOST.
localizer::FramePose frame_pose_of(const frame_pose_t& m);

// Pose2 from a pose_t (yaw of its quaternion).
Pose2 pose2_of(const pose_t& m);

// The localization map of a node's `plan` option (path relative to the graph, layer globs, units) with
// the named look-up ("" = annf-exact). Throws naming `node_field`.plan.file when no plan is given.
LocalizationMap load_map(const rt::Context& ctx, const PlanSource& plan, const std::string& lookup,
                         const std::string& node_field);

}  // namespace fploc
