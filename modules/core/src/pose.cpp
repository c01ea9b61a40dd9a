#include "fploc/core/pose.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace fploc {

double wrap_angle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a <= 0) a += 2.0 * M_PI;
  return a - M_PI;
}

Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrap_angle(a.yaw + b.yaw)};
}

Pose2 interpolate(const Pose2& a, const Pose2& b, double f) {
  const Pose2 d = between(a, b);
  return compose(a, Pose2{f * d.x, f * d.y, f * d.yaw});
}

Pose2 inverse(const Pose2& a) {
  const double c = std::cos(a.yaw), s = std::sin(a.yaw);
  return {-c * a.x - s * a.y, s * a.x - c * a.y, wrap_angle(-a.yaw)};
}

Eigen::Isometry3d StampedPose::iso() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = p;
  return T;
}

StampedPose StampedPose::from(double t, const Eigen::Isometry3d& T) {
  StampedPose s;
  s.t = t;
  s.p = T.translation();
  s.q = Eigen::Quaterniond(T.linear()).normalized();
  return s;
}

StampedPose StampedPose::from_rpy(double t, const Eigen::Vector3d& p, double roll, double pitch, double yaw) {
  StampedPose s;
  s.t = t;
  s.p = p;
  s.q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
        Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  return s;
}

Eigen::Vector3d StampedPose::rpy() const {
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return {roll, pitch, yaw};
}

std::string tum_line(const StampedPose& p) {
  Eigen::Quaterniond q = p.q.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f", p.t, p.p.x(), p.p.y(), p.p.z(), q.x(),
                q.y(), q.z(), q.w());
  return buf;
}

Trajectory read_tum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  Trajectory out;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ss(line);
    StampedPose s;
    double qx, qy, qz, qw;
    if (!(ss >> s.t >> s.p.x() >> s.p.y() >> s.p.z() >> qx >> qy >> qz >> qw)) {
      throw std::runtime_error(path + ":" + std::to_string(lineno) + ": expected 8 numbers 't x y z qx qy qz qw'");
    }
    const double n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
    if (!std::isfinite(n) || n < 1e-9 || !std::isfinite(s.t) || !s.p.allFinite()) {
      throw std::runtime_error(path + ":" + std::to_string(lineno) + ": non-finite value or zero quaternion");
    }
    s.q = Eigen::Quaterniond(qw / n, qx / n, qy / n, qz / n);
    out.push_back(s);
  }
  return out;
}

void write_tum(const std::string& path, const Trajectory& traj) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  for (const auto& p : traj) out << tum_line(p) << '\n';
}

}  // namespace fploc
