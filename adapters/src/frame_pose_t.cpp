#include "fploc/adapters/frame_pose_t.h"

#include <cmath>
#include <string>

namespace fploc::adapters {

frame_pose_t to_msg(const localizer::FramePose& f, int64_t seq, double solve_ms) {
  const matcher::MatchResult& r = f.match;
  frame_pose_t o;
  o.utime = f.utime;
  o.seq = seq;
  o.scan_seq = f.scan_seq;
  o.status = int8_t(r.status);
  o.status_text = r.status == matcher::FitStatus::kOk ? "" : std::string(to_string(r.status)) + ": " + r.text;
  o.x = r.pose.x;
  o.y = r.pose.y;
  o.yaw = r.pose.yaw;
  for (int i = 0; i < 9; ++i) o.covariance[i] = r.covariance(i / 3, i % 3);
  o.roll = f.roll;
  o.pitch = f.pitch;
  o.z = f.z;
  o.twist[0] = r.twist.vx;
  o.twist[1] = r.twist.vy;
  o.twist[2] = r.twist.w;
  o.num_points = r.fit.num_points;
  o.num_inliers = r.fit.num_inliers;
  o.inlier_ratio = r.fit.inlier_ratio;
  o.rms_residual_m = r.fit.rms_m;
  o.iterations = r.iterations;
  o.solve_ms = solve_ms;
  o.floor_index = int16_t(f.floor_index);
  o.floor = f.floor;
  o.z_sigma = f.z_sigma;
  return o;
}

localizer::FramePose from_msg(const frame_pose_t& m) {
  localizer::FramePose f;
  f.utime = m.utime;
  f.scan_seq = m.scan_seq;
  f.match.pose = {m.x, m.y, m.yaw};
  if (std::isfinite(m.twist[0]) && std::isfinite(m.twist[1]) && std::isfinite(m.twist[2]))
    f.match.twist = {m.twist[0], m.twist[1], m.twist[2]};
  f.match.status = m.status >= 0 && m.status <= 3 ? matcher::FitStatus(m.status) : matcher::FitStatus::kLost;
  f.match.text = m.status_text;
  // to_msg writes "STATUS: text": the text without its status (else the optimizer's log said "POOR: POOR: ...").
  const std::string prefix = std::string(to_string(f.match.status)) + ": ";
  if (f.match.text.compare(0, prefix.size(), prefix) == 0) f.match.text.erase(0, prefix.size());
  for (int i = 0; i < 9; ++i) f.match.covariance(i / 3, i % 3) = m.covariance[i];
  f.match.fit.num_points = m.num_points;
  f.match.fit.num_inliers = m.num_inliers;
  f.match.fit.inlier_ratio = m.inlier_ratio;
  f.match.fit.rms_m = m.rms_residual_m;
  f.match.iterations = m.iterations;
  f.roll = m.roll;
  f.pitch = m.pitch;
  f.z = m.z;
  f.floor_index = m.floor_index;
  f.floor = m.floor;
  f.z_sigma = std::isfinite(m.z_sigma) ? m.z_sigma : f.z_sigma;
  return f;
}

}  // namespace fploc::adapters
