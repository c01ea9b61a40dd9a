#include "fploc/adapters/features_t.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace fploc::adapters {

void to_msg(const FeatureFrame& f, int64_t seq, features_t& m) {
  m.utime = f.utime;
  m.seq = seq;
  m.scan_seq = f.scan_seq;
  m.status = int8_t(f.status);
  m.roll = f.roll;
  m.pitch = f.pitch;
  m.z = f.z;
  m.roll_pitch_sigma = f.roll_pitch_sigma;
  m.z_sigma = f.z_sigma;
  m.attitude_t_offset_s = f.attitude_t;
  const size_t n = f.points.size();
  m.num_points = int32_t(n);
  m.x.resize(n);
  m.y.resize(n);
  m.kind.resize(n);
  m.group.resize(n);
  m.t_offset_s.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Feature2& p = f.points[i];
    m.x[i] = float(p.p.x());
    m.y[i] = float(p.p.y());
    m.kind[i] = int8_t(p.kind);
    m.group[i] = p.group;
    m.t_offset_s[i] = p.t;
  }
  m.num_groups = f.num_groups;
}

FeatureFrame from_msg(const features_t& m, int* dropped) {
  const size_t n = size_t(std::max(0, m.num_points));
  if (m.x.size() != n || m.y.size() != n || m.kind.size() != n || m.group.size() != n || m.t_offset_s.size() != n)
    throw std::runtime_error("features_t seq " + std::to_string(m.seq) + ": arrays x/y/kind/group/t_offset_s disagree with num_points " +
                             std::to_string(m.num_points));
  FeatureFrame f;
  f.utime = m.utime;
  f.scan_seq = m.scan_seq;
  f.status = m.status >= 0 && m.status <= 2 ? FeatureStatus(m.status) : FeatureStatus::kBadInput;
  f.roll = m.roll;
  f.pitch = m.pitch;
  f.z = m.z;
  f.roll_pitch_sigma = std::isfinite(m.roll_pitch_sigma) ? m.roll_pitch_sigma : 0;
  f.z_sigma = std::isfinite(m.z_sigma) ? m.z_sigma : 0;
  f.attitude_t = std::isfinite(m.attitude_t_offset_s) ? m.attitude_t_offset_s : 0;
  f.num_groups = m.num_groups;
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

}  // namespace fploc::adapters
