#include "fploc/adapters/pose_t.h"

#include <Eigen/Geometry>
#include <cmath>

namespace fploc::adapters {

pose_t make_pose_msg(int64_t utime, int64_t seq, const Pose2& p, double roll, double pitch, double z,
                     const Eigen::Matrix3d& c, double z_sigma, double rp_sigma, int8_t status, bool keyframe,
                     bool final_estimate, int floor_index, const std::string& floor) {
  pose_t m;
  m.utime = utime;
  m.seq = seq;
  m.status = status;
  m.keyframe = keyframe;
  m.final_estimate = final_estimate;
  m.floor_index = int16_t(floor_index);
  m.floor = floor;
  const StampedPose sp = StampedPose::from_rpy(0, Eigen::Vector3d(p.x, p.y, z), roll, pitch, p.yaw);
  m.position[0] = sp.p.x();
  m.position[1] = sp.p.y();
  m.position[2] = sp.p.z();
  m.orientation[0] = sp.q.x();
  m.orientation[1] = sp.q.y();
  m.orientation[2] = sp.q.z();
  m.orientation[3] = sp.q.w();
  for (double& v : m.covariance) v = 0;
  // order x y z roll pitch yaw; (x, y, yaw) -> indices 0, 1, 5
  const int idx[3] = {0, 1, 5};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.covariance[idx[i] * 6 + idx[j]] = c(i, j);
  m.covariance[2 * 6 + 2] = z_sigma * z_sigma;
  m.covariance[3 * 6 + 3] = rp_sigma * rp_sigma;
  m.covariance[4 * 6 + 4] = rp_sigma * rp_sigma;
  return m;
}

Eigen::Matrix3d xy_yaw_covariance(const pose_t& m) {
  const int idx[3] = {0, 1, 5};
  Eigen::Matrix3d c;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i, j) = m.covariance[idx[i] * 6 + idx[j]];
  return c;
}

pose_t to_msg(const optimizer::PoseOut& p, int64_t seq, int floor_index, const std::string& floor) {
  return make_pose_msg(p.utime, seq, p.pose, p.roll, p.pitch, p.z, p.covariance, p.z_sigma, p.roll_pitch_sigma,
                       int8_t(p.status), p.keyframe, p.final_estimate, floor_index, floor);
}

Pose2 pose2_of(const pose_t& m) {
  StampedPose sp;
  sp.q = Eigen::Quaterniond(m.orientation[3], m.orientation[0], m.orientation[1], m.orientation[2]);
  if (sp.q.squaredNorm() < 1e-12) sp.q = Eigen::Quaterniond::Identity();
  sp.q.normalize();
  return {m.position[0], m.position[1], sp.rpy()[2]};
}

std::optional<Pose2> finite_pose2_of(const pose_t& m) {
  const Pose2 p = pose2_of(m);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw)) return std::nullopt;
  return p;
}

}  // namespace fploc::adapters
