#include "tf_tree.h"

#include <algorithm>
#include <cstdlib>

namespace fploc::import {
namespace {
Eigen::Isometry3d iso(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = p;
  return T;
}
}  // namespace

std::string TfTree::bare(const std::string& f) { return !f.empty() && f[0] == '/' ? f.substr(1) : f; }

void TfTree::add(const rec::Transform& t) {
  auto& e = edges_[bare(t.child_frame_id)];
  const Sample smp{t.header.stamp_ns, Eigen::Vector3d(t.t[0], t.t[1], t.t[2]),
                   Eigen::Quaterniond(t.q[3], t.q[0], t.q[1], t.q[2]).normalized()};
  if (gap_ns_ > 0 && !e.samples.empty()) {
    const Sample last = e.samples.back();
    if (smp.p == last.p && smp.q.coeffs() == last.q.coeffs()) {  // unchanged: held until then
      e.held_until_ns = std::max(e.held_until_ns, smp.t_ns);
      return;
    }
    if (std::abs(smp.t_ns - last.t_ns) < gap_ns_) return;
    // The last value held until it was last published: a sample of it there, so that it does not blend into this
    // one over the whole time it held.
    if (e.held_until_ns > last.t_ns && e.held_until_ns < smp.t_ns) e.samples.push_back({e.held_until_ns, last.p, last.q});
    e.held_until_ns = INT64_MIN;
  }
  e.parent = bare(t.header.frame_id);
  e.samples.push_back(smp);
}

void TfTree::sort() {
  for (auto& [c, e] : edges_) {
    if (!e.samples.empty() && e.held_until_ns > e.samples.back().t_ns) {
      const Sample last = e.samples.back();
      e.samples.push_back({e.held_until_ns, last.p, last.q});
    }
    e.held_until_ns = INT64_MIN;
    std::stable_sort(e.samples.begin(), e.samples.end(), [](const Sample& a, const Sample& b) { return a.t_ns < b.t_ns; });
  }
}

bool TfTree::has(const std::string& frame) const { return frames().count(bare(frame)) > 0; }

std::set<std::string> TfTree::frames() const {
  std::set<std::string> f;
  for (const auto& [c, e] : edges_) f.insert(c), f.insert(e.parent);
  return f;
}

std::optional<TfTree::Path> TfTree::path(const std::string& parent_frame, const std::string& child_frame) const {
  const std::string parent = bare(parent_frame), child = bare(child_frame);
  if (!has(parent) || !has(child)) return std::nullopt;
  auto chain = [&](std::string f) {  // f, its parent, ... up to the root
    std::vector<std::string> c{f};
    for (int i = 0; i < 64; ++i) {
      auto e = edges_.find(f);
      if (e == edges_.end()) break;
      f = e->second.parent;
      c.push_back(f);
    }
    return c;
  };
  const auto a = chain(parent), b = chain(child);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (a[i] == b[j]) {
        Path p;
        for (size_t k = 0; k < i; ++k) p.up_parent.push_back(&edges_.at(a[k]));
        for (size_t k = 0; k < j; ++k) p.up_child.push_back(&edges_.at(b[k]));
        p.start_ns = INT64_MIN;
        for (const auto* v : {&p.up_parent, &p.up_child})
          for (const Edge* e : *v) {
            p.start_ns = std::max(p.start_ns, e->samples.front().t_ns);
            for (const auto& s : e->samples) p.times_ns.insert(s.t_ns);
          }
        return p;
      }
  return std::nullopt;
}

Eigen::Isometry3d TfTree::at(const Edge& e, int64_t t) {
  const auto& s = e.samples;
  auto hi = std::lower_bound(s.begin(), s.end(), t, [](const Sample& a, int64_t v) { return a.t_ns < v; });
  if (hi == s.begin()) return iso(s.front().p, s.front().q);
  if (hi == s.end()) return iso(s.back().p, s.back().q);
  if (hi->t_ns == t) return iso(hi->p, hi->q);
  const auto lo = hi - 1;
  const double a = double(t - lo->t_ns) / double(hi->t_ns - lo->t_ns);
  return iso(lo->p + a * (hi->p - lo->p), lo->q.slerp(a, hi->q));
}

Eigen::Isometry3d TfTree::at(const Path& p, int64_t t) {
  Eigen::Isometry3d Ta = Eigen::Isometry3d::Identity(), Tb = Eigen::Isometry3d::Identity();  // ancestor <- frame
  for (const Edge* e : p.up_parent) Ta = at(*e, t) * Ta;
  for (const Edge* e : p.up_child) Tb = at(*e, t) * Tb;
  return Ta.inverse() * Tb;
}

}  // namespace fploc::import
