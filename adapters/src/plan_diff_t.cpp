#include "fploc/adapters/plan_diff_t.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace fploc::adapters {

plandiff::PlanDiff::Heights heights_of(const segments_t& m) {
  plandiff::PlanDiff::Heights h;
  h.sensor_z = m.z;
  const size_t n = size_t(std::max(0, m.num_points));
  if (m.status != 0 || !std::isfinite(m.roll) || !std::isfinite(m.pitch) || !std::isfinite(m.z) ||
      m.x.size() < n || m.y.size() < n || m.z_pts.size() < n)
    return h;
  const Eigen::Matrix3f R = (Eigen::AngleAxisf(float(m.pitch), Eigen::Vector3f::UnitY()) *
                             Eigen::AngleAxisf(float(m.roll), Eigen::Vector3f::UnitX()))
                                .toRotationMatrix();
  h.points.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p(m.x[i], m.y[i], m.z_pts[i]);
    if (p.allFinite()) h.points.push_back(R * p);
  }
  return h;
}

plan_diff_t to_msg(const plandiff::Diff& r, const FloorPlan& plan, int64_t utime, int64_t seq) {
  using plandiff::Status;
  plan_diff_t msg;
  msg.utime = utime;
  msg.seq = seq;
  msg.frames = r.frames;
  msg.elements_seen = r.count(Status::kSeen);
  msg.elements_missing = r.count(Status::kMissing);
  msg.elements_moved = r.count(Status::kMoved);
  msg.elements_unobserved = r.count(Status::kUnobserved);
  msg.scale_error = r.scale_error;
  msg.scale_sigma = r.scale_sigma;
  auto item = [&](PlanDiffKind kind, int32_t el, bool circle, double x0, double y0, double x1, double y1, double off,
                  double ratio) {
    msg.kind.push_back(int8_t(kind));
    msg.circle.push_back(circle);
    msg.element.push_back(el);
    msg.x0.push_back(float(x0));
    msg.y0.push_back(float(y0));
    msg.x1.push_back(float(x1));
    msg.y1.push_back(float(y1));
    msg.offset_m.push_back(float(off));
    msg.seen_ratio.push_back(float(ratio));
  };
  for (const auto& e : r.elements) {
    if (e.status != Status::kMissing && e.status != Status::kMoved) continue;
    const auto& p = plan.elements[size_t(e.id)];
    const double off = e.status == Status::kMoved ? e.offset_m : 0.0;
    const PlanDiffKind kind = e.status == Status::kMissing ? PlanDiffKind::kMissing : PlanDiffKind::kMoved;
    if (p.kind == ElementKind::kSegment) {
      const Eigen::Vector2d u = (p.b - p.a).normalized(), s = off * Eigen::Vector2d(-u.y(), u.x());
      item(kind, e.id, false, p.a.x() + s.x(), p.a.y() + s.y(), p.b.x() + s.x(), p.b.y() + s.y(), off, e.seen_ratio());
    } else {
      item(kind, e.id, true, p.c.x(), p.c.y(), p.r + off, 0, off, e.seen_ratio());
    }
  }
  for (const auto& n : r.added) item(PlanDiffKind::kNew, n.extends, false, n.a.x(), n.a.y(), n.b.x(), n.b.y(), n.rms_m, 0);
  for (const auto& n : r.low) item(PlanDiffKind::kLow, n.extends, false, n.a.x(), n.a.y(), n.b.x(), n.b.y(), n.top_m, 0);
  for (const auto& m : r.missing_parts)
    item(PlanDiffKind::kMissingPart, m.element, false, m.a.x(), m.a.y(), m.b.x(), m.b.y(), 0,
         m.expected ? double(m.seen) / double(m.expected) : 0.0);
  msg.num_items = int32_t(msg.kind.size());
  for (const auto& rs : r.refined) {
    msg.refined_element.push_back(rs.element);
    msg.refined_offset_a.push_back(float(rs.offset_a));
    msg.refined_offset_b.push_back(float(rs.offset_b));
  }
  msg.num_refined = int32_t(msg.refined_element.size());
  return msg;
}

std::vector<matcher::FlaggedElement> flagged_elements(const plan_diff_t& m) {
  std::vector<matcher::FlaggedElement> out;
  const size_t n = size_t(std::max(0, m.num_items));
  for (size_t i = 0; i < n && i < m.kind.size() && i < m.element.size(); ++i) {
    if (m.element[i] < 0) continue;
    if (m.kind[i] == int8_t(PlanDiffKind::kMissing)) out.push_back({m.element[i], matcher::DiffVerdict::kMissing});
    else if (m.kind[i] == int8_t(PlanDiffKind::kMoved)) out.push_back({m.element[i], matcher::DiffVerdict::kMoved});
  }
  return out;
}

std::vector<matcher::SegmentOffset> refined_offsets(const plan_diff_t& m) {
  std::vector<matcher::SegmentOffset> out;
  const size_t n = size_t(std::max(0, m.num_refined));
  for (size_t i = 0; i < n && i < m.refined_element.size() && i < m.refined_offset_a.size() && i < m.refined_offset_b.size(); ++i)
    if (m.refined_element[i] >= 0 && std::isfinite(m.refined_offset_a[i]) && std::isfinite(m.refined_offset_b[i]))
      out.push_back({m.refined_element[i], m.refined_offset_a[i], m.refined_offset_b[i]});
  return out;
}

}  // namespace fploc::adapters
