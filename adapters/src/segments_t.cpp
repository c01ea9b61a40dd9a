#include "fploc/adapters/segments_t.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace fploc::adapters {

void to_msg(const seg::Segmentation& s, int64_t seq, segments_t& m) {
  m.utime = s.utime;
  m.seq = seq;
  m.scan_seq = s.seq;
  m.status = int8_t(s.status);
  m.status_text = s.status_text;
  m.ceiling_found = s.ceiling.found;
  m.ground_found = s.ground.found;
  for (int k = 0; k < 4; ++k) {
    m.ceiling_plane[k] = s.ceiling.coeffs[k];
    m.ground_plane[k] = s.ground.coeffs[k];
  }
  m.ceiling_inliers = s.ceiling.inliers;
  m.ceiling_rms_m = s.ceiling.rms_m;
  m.ground_inliers = s.ground.inliers;
  m.ground_rms_m = s.ground.rms_m;
  m.roll = s.roll;
  m.pitch = s.pitch;
  m.z = s.z;
  m.roll_pitch_sigma = s.roll_pitch_sigma;
  m.z_sigma = s.z_sigma;
  m.attitude_source = int8_t(s.attitude_source);
  m.z_source = int8_t(s.z_source);
  m.attitude_t_offset_s = s.attitude_t;  // 3 = none (no ceiling, no history, no IMU)
  m.height = int16_t(s.height);
  m.width = int16_t(s.width);
  const auto& w = s.wall;
  m.num_points = int32_t(w.size());
  m.x = w.x;
  m.y = w.y;
  m.z_pts = w.z;
  m.ring = w.ring;
  m.column = w.column;
  m.range_m = w.range;
  m.t_offset_s = w.t.size() == w.size() ? w.t : std::vector<float>(w.size(), 0.f);
}

void from_msg(const segments_t& m, seg::Segmentation& s) {
  const size_t n = size_t(std::max(0, m.num_points));
  auto bad = [&](const std::string& what) {
    throw std::runtime_error("segments_t seq " + std::to_string(m.seq) + ": " + what);
  };
  if (m.num_points < 0) bad("num_points < 0");
  if (m.x.size() != n || m.y.size() != n || m.z_pts.size() != n || m.ring.size() != n || m.column.size() != n ||
      m.range_m.size() != n || m.t_offset_s.size() != n)
    bad("x/y/z_pts/ring/column/range_m/t_offset_s sizes disagree with num_points " + std::to_string(n));
  s.utime = m.utime;
  s.seq = m.scan_seq;
  s.status = seg::SegStatus(m.status);
  s.status_text = m.status_text;
  s.ceiling.found = m.ceiling_found;
  s.ground.found = m.ground_found;
  for (int k = 0; k < 4; ++k) {
    s.ceiling.coeffs[k] = m.ceiling_plane[k];
    s.ground.coeffs[k] = m.ground_plane[k];
  }
  s.ceiling.inliers = m.ceiling_inliers;
  s.ceiling.rms_m = m.ceiling_rms_m;
  s.ground.inliers = m.ground_inliers;
  s.ground.rms_m = m.ground_rms_m;
  s.roll = m.roll;
  s.pitch = m.pitch;
  s.z = m.z;
  s.roll_pitch_sigma = m.roll_pitch_sigma;
  s.z_sigma = m.z_sigma;
  s.attitude_source = seg::AttitudeSource(m.attitude_source);
  s.z_source = seg::HeightSource(m.z_source);
  s.attitude_t = std::isfinite(m.attitude_t_offset_s) ? m.attitude_t_offset_s : 0.0;
  s.height = m.height;
  s.width = m.width;
  auto& w = s.wall;
  w.x = m.x;
  w.y = m.y;
  w.z = m.z_pts;
  w.ring = m.ring;
  w.column = m.column;
  w.range = m.range_m;
  w.t = m.t_offset_s;
  // The feature extractor needs ring-major, increasing columns; check instead of trusting.
  for (size_t i = 1; i < n; ++i)
    if (w.ring[i] < w.ring[i - 1] || (w.ring[i] == w.ring[i - 1] && w.column[i] <= w.column[i - 1]))
      bad("wall points not ring-major with increasing column at index " + std::to_string(i));
}

}  // namespace fploc::adapters
