#include "tum_track.h"

#include <algorithm>
#include <set>

namespace fploc::import {
namespace {
std::string strip(std::string s) { return !s.empty() && s[0] == '/' ? s.substr(1) : s; }  // "/odom" == "odom"
Eigen::Isometry3d iso(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = p;
  return T;
}
Eigen::Quaterniond quat(const rec::Transform& t) { return Eigen::Quaterniond(t.q[3], t.q[0], t.q[1], t.q[2]).normalized(); }
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

Eigen::Isometry3d TumTrack::at(const Edge& e, int64_t t) {
  const auto& s = e.samples;
  auto hi = std::lower_bound(s.begin(), s.end(), t, [](const Sample& a, int64_t v) { return a.t_ns < v; });
  if (hi == s.begin()) return iso(s.front().p, s.front().q);
  if (hi == s.end()) return iso(s.back().p, s.back().q);
  if (hi->t_ns == t) return iso(hi->p, hi->q);
  const auto lo = hi - 1;
  const double a = double(t - lo->t_ns) / double(hi->t_ns - lo->t_ns);
  return iso(lo->p + a * (hi->p - lo->p), lo->q.slerp(a, hi->q));
}

void TumTrack::tf(const rec::Transform& t) {
  if (parent_.empty()) return;
  auto& e = edges_[strip(t.child_frame_id)];
  e.parent = strip(t.header.frame_id);
  e.samples.push_back({t.header.stamp_ns, Eigen::Vector3d(t.t[0], t.t[1], t.t[2]), quat(t)});
}

void TumTrack::odometry(const rec::Odometry& o) {
  write(o.pose.header.stamp_ns, iso(Eigen::Vector3d(o.pose.t[0], o.pose.t[1], o.pose.t[2]), quat(o.pose)));
}

void TumTrack::close() {
  if (f_ && !parent_.empty()) {
    for (auto& [c, e] : edges_)
      std::stable_sort(e.samples.begin(), e.samples.end(), [](const Sample& a, const Sample& b) { return a.t_ns < b.t_ns; });
    // The two chains frame -> root, joined at the first common ancestor.
    auto chain = [&](std::string f) {
      std::vector<std::string> c{f};
      for (int i = 0; i < 64; ++i) {
        auto e = edges_.find(f);
        if (e == edges_.end()) break;
        f = e->second.parent;
        c.push_back(f);
      }
      return c;
    };
    const auto a = chain(parent_), b = chain(child_);
    size_t ia = a.size(), ib = b.size();
    for (size_t i = 0; i < a.size() && ia == a.size(); ++i)
      for (size_t j = 0; j < b.size(); ++j)
        if (a[i] == b[j]) {
          ia = i;
          ib = j;
          break;
        }
    if (ia < a.size()) {
      // Edges below the common ancestor: a[0..ia) (parent's side), b[0..ib) (child's side).
      std::vector<const Edge*> up_a, up_b;
      for (size_t i = 0; i < ia; ++i) up_a.push_back(&edges_.at(a[i]));
      for (size_t j = 0; j < ib; ++j) up_b.push_back(&edges_.at(b[j]));
      int64_t start = INT64_MIN;
      std::set<int64_t> times;
      for (const auto* v : {&up_a, &up_b})
        for (const Edge* e : *v) {
          start = std::max(start, e->samples.front().t_ns);
          for (const auto& s : e->samples) times.insert(s.t_ns);
        }
      for (const int64_t t : times) {
        if (t < start) continue;
        Eigen::Isometry3d Ta = Eigen::Isometry3d::Identity(), Tb = Eigen::Isometry3d::Identity();  // root <- frame
        for (const Edge* e : up_a) Ta = at(*e, t) * Ta;
        for (const Edge* e : up_b) Tb = at(*e, t) * Tb;
        write(t, Ta.inverse() * Tb);  // T_parent_child
      }
    }
  }
  if (f_) std::fclose(f_);
  f_ = nullptr;
}

}  // namespace fploc::import
