#include "fploc/nodes/localization_convert.h"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "fploc/core/pose.h"
#include "fploc/runtime/node.h"

namespace fploc {

FeatureFrame from_msg(const features_t& m, int* dropped) {
  const size_t n = size_t(std::max(0, m.num_points));
  if (m.x.size() != n || m.y.size() != n || m.kind.size() != n || m.group.size() != n || m.t_offset_s.size() != n)
    throw std::runtime_error("features_t seq " + std::to_string(m.seq) + ": arrays x/y/kind/group/t_offset_s disagree with num_points " +
                             std::to_string(m.num_points));
  FeatureFrame f;
  f.utime = m.utime;
  f.scan_seq = m.scan_seq;
  f.roll = m.roll;
  f.pitch = m.pitch;
  f.z = m.z;
  f.roll_pitch_sigma = std::isfinite(m.roll_pitch_sigma) ? m.roll_pitch_sigma : 0;
  f.z_sigma = std::isfinite(m.z_sigma) ? m.z_sigma : 0;
  f.attitude_t = std::isfinite(m.attitude_t_offset_s) ? m.attitude_t_offset_s : 0;
  f.points.reserve(n);
  int bad = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(m.x[i]) || !std::isfinite(m.y[i])) {
      ++bad;
      continue;
    }
    Feature2 p;
    p.p = {double(m.x[i]), double(m.y[i])};
    p.kind = m.kind[i] == 0 ? FeatureKind::kCorner : FeatureKind::kSurface;
    p.group = m.group[i];
    p.t = std::isfinite(m.t_offset_s[i]) ? m.t_offset_s[i] : 0.f;
    f.points.push_back(p);
  }
  if (!std::isfinite(f.roll)) f.roll = 0;
  if (!std::isfinite(f.pitch)) f.pitch = 0;
  if (!std::isfinite(f.z)) f.z = 0;
  if (dropped) *dropped = bad;
  return f;
}

pose_t make_pose_msg(int64_t utime, int64_t seq, const Pose2& p, double roll, double pitch, double z,
                     const Eigen::Matrix3d& c, double z_sigma, double rp_sigma, int8_t status, bool keyframe,
                     bool final_estimate) {
  pose_t m;
  m.utime = utime;
  m.seq = seq;
  m.status = status;
  m.keyframe = keyframe;
  m.final_estimate = final_estimate;
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

pose_t to_msg(const localizer::Pose& p, int64_t seq) {
  return make_pose_msg(p.utime, seq, p.pose, p.roll, p.pitch, p.z, p.covariance, p.z_sigma, p.roll_pitch_sigma,
                       int8_t(p.status), p.keyframe, p.final_estimate);
}

localizer::FramePose frame_pose_of(const frame_pose_t& m) {
  localizer::FramePose f;
  f.utime = m.utime;
  f.scan_seq = m.scan_seq;
  f.match.pose = {m.x, m.y, m.yaw};
  if (std::isfinite(m.twist[0]) && std::isfinite(m.twist[1]) && std::isfinite(m.twist[2]))
    f.match.twist = {m.twist[0], m.twist[1], m.twist[2]};
  f.match.status = m.status >= 0 && m.status <= 3 ? FitStatus(m.status) : FitStatus::kLost;
  for (int i = 0; i < 9; ++i) f.match.covariance(i / 3, i % 3) = m.covariance[i];
  f.roll = m.roll;
  f.pitch = m.pitch;
  f.z = m.z;
  return f;
}

Pose2 pose2_of(const pose_t& m) {
  StampedPose sp;
  sp.q = Eigen::Quaterniond(m.orientation[3], m.orientation[0], m.orientation[1], m.orientation[2]);
  if (sp.q.squaredNorm() < 1e-12) sp.q = Eigen::Quaterniond::Identity();
  sp.q.normalize();
  return {m.position[0], m.position[1], sp.rpy()[2]};
}

LocalizationMap load_map(const rt::Context& ctx, const PlanSource& plan, const std::string& lookup,
                         const std::string& node_field) {
  if (plan.file().empty()) throw std::runtime_error(node_field + ".plan.file: no floor plan given");
  const std::vector<std::string> layers(plan.layers().begin(), plan.layers().end());
  return load_localization_map(ctx.resolve_path(plan.file()), layers, plan.units(), lookup.empty() ? "annf-exact" : lookup);
}

}  // namespace fploc
