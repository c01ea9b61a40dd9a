#include "tum_track.h"

namespace fploc::import {
namespace {
Eigen::Isometry3d iso(const rec::Transform& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(t.q[3], t.q[0], t.q[1], t.q[2]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.t[0], t.t[1], t.t[2]);
  return T;
}
std::string strip(std::string s) { return !s.empty() && s[0] == '/' ? s.substr(1) : s; }  // "/odom" == "odom"
}  // namespace

bool TumTrack::open(const std::string& path, const std::string& parent, const std::string& child) {
  f_ = std::fopen(path.c_str(), "w");
  parent_ = strip(parent);
  child_ = strip(child);
  return f_ != nullptr;
}

void TumTrack::write(int64_t t_ns, const Eigen::Isometry3d& T) {
  if (!f_ || t_ns == last_t_) return;  // one pose per time stamp
  last_t_ = t_ns;
  const Eigen::Quaterniond q(T.linear());
  std::fprintf(f_, "%.9f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", double(t_ns) * 1e-9, T.translation().x(),
               T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w());
  ++poses_;
}

bool TumTrack::lookup(const std::string& from, const std::string& to, Eigen::Isometry3d& T) const {
  // Chains child -> root for both frames, joined at the first common ancestor.
  auto chain = [&](std::string f) {
    std::vector<std::pair<std::string, Eigen::Isometry3d>> c;  // (frame, T_root..frame accumulated)
    Eigen::Isometry3d acc = Eigen::Isometry3d::Identity();
    c.push_back({f, acc});
    for (int i = 0; i < 64; ++i) {
      auto e = edges_.find(f);
      if (e == edges_.end()) break;
      acc = e->second.second * acc;  // T_parent_frame0
      f = e->second.first;
      c.push_back({f, acc});
    }
    return c;
  };
  const auto a = chain(from), b = chain(to);
  for (const auto& [fa, Ta] : a)
    for (const auto& [fb, Tb] : b)
      if (fa == fb) {
        T = Ta.inverse() * Tb;  // T_from_to
        return true;
      }
  return false;
}

void TumTrack::tf(const rec::Transform& t) {
  const std::string p = strip(t.header.frame_id), c = strip(t.child_frame_id);
  edges_[c] = {p, iso(t)};
  if (parent_.empty()) return;
  // A pose per update of an edge on the child's path to the parent (not for unrelated frames).
  bool on_path = false;
  std::string f = child_;
  for (int i = 0; i < 64 && f != parent_; ++i) {
    if (f == c) {
      on_path = true;
      break;
    }
    auto e = edges_.find(f);
    if (e == edges_.end()) break;
    f = e->second.first;
  }
  Eigen::Isometry3d T;
  if (on_path && lookup(parent_, child_, T)) write(t.header.stamp_ns, T);
}

void TumTrack::odometry(const rec::Odometry& o) { write(o.pose.header.stamp_ns, iso(o.pose)); }

void TumTrack::close() {
  if (f_) std::fclose(f_);
  f_ = nullptr;
}

}  // namespace fploc::import
