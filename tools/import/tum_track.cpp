#include "tum_track.h"

namespace fploc::import {

bool TumTrack::open(const std::string& path, const std::string& parent, const std::string& child) {
  f_ = std::fopen(path.c_str(), "w");
  parent_ = TfTree::bare(parent);
  child_ = TfTree::bare(child);
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

void TumTrack::tf(const rec::Transform& t) {
  if (!parent_.empty()) tree_.add(t);
}

void TumTrack::odometry(const rec::Odometry& o) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(o.pose.q[3], o.pose.q[0], o.pose.q[1], o.pose.q[2]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(o.pose.t[0], o.pose.t[1], o.pose.t[2]);
  write(o.pose.header.stamp_ns, T);
}

void TumTrack::close() {
  if (f_ && !parent_.empty()) {
    tree_.sort();
    if (const auto p = tree_.path(parent_, child_))
      for (const int64_t t : p->times_ns)
        if (t >= p->start_ns) write(t, TfTree::at(*p, t));
  }
  if (f_) std::fclose(f_);
  f_ = nullptr;
}

}  // namespace fploc::import
