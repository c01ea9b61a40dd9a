#include "fploc/adapters/scan_t.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace fploc::adapters {

void to_msg(const Scan& s, scan_t& m) {
  m.utime = s.utime;
  m.seq = s.seq;
  m.frame_id = s.frame_id;
  m.sensor = s.sensor;
  m.height = int16_t(s.height);
  m.width = int16_t(s.width);
  const size_t n = size_t(s.height) * s.width;
  m.num_pixels = int32_t(n);
  m.range_mm.assign(s.range_mm.begin(), s.range_mm.end());
  m.signal.resize(n);
  m.reflectivity.resize(n);
  for (size_t i = 0; i < n; ++i) {
    m.signal[i] = i < s.signal.size() ? int16_t(std::min<uint32_t>(s.signal[i], 32767)) : 0;
    m.reflectivity[i] = i < s.reflectivity.size() ? s.reflectivity[i] : 0;
  }
  m.column_utime = s.column_utime;
  m.column_utime.resize(s.width, s.utime);
  m.measurement_id.resize(s.width);
  m.column_valid.resize(s.width);
  for (int c = 0; c < s.width; ++c) {
    m.measurement_id[c] = c < int(s.measurement_id.size()) ? int16_t(s.measurement_id[c]) : int16_t(c);
    m.column_valid[c] = c < int(s.column_valid.size()) ? s.column_valid[c] != 0 : true;
  }
  const auto& b = s.beams;
  m.beam_altitude_deg.assign(b.altitude_deg.begin(), b.altitude_deg.end());
  m.beam_azimuth_deg.assign(b.azimuth_deg.begin(), b.azimuth_deg.end());
  m.pixel_shift_by_row.resize(s.height);
  for (int u = 0; u < s.height; ++u)
    m.pixel_shift_by_row[u] = u < int(b.pixel_shift_by_row.size()) ? int16_t(b.pixel_shift_by_row[u]) : 0;
  m.beam_altitude_deg.resize(s.height, 0.f);
  m.beam_azimuth_deg.resize(s.height, 0.f);
  m.lidar_origin_to_beam_origin_mm = float(b.beam_offset_mm);
  std::copy(b.lidar_to_sensor.begin(), b.lidar_to_sensor.end(), m.lidar_to_sensor);
  m.missing_columns = s.missing_columns;
  m.status = int8_t(s.status);
}

void from_msg(const scan_t& m, Scan& s) {
  auto bad = [&](const std::string& what) {
    throw std::runtime_error("scan_t seq " + std::to_string(m.seq) + ": " + what);
  };
  if (m.height <= 0 || m.width <= 0) bad("empty scan (height " + std::to_string(m.height) + ", width " + std::to_string(m.width) + ")");
  if (m.num_pixels != int32_t(m.height) * m.width) bad("num_pixels != height*width");
  if (int(m.beam_altitude_deg.size()) != m.height) bad("beam count of intrinsics != height");
  s.utime = m.utime;
  s.seq = m.seq;
  s.frame_id = m.frame_id;
  s.sensor = m.sensor;
  s.height = m.height;
  s.width = m.width;
  const size_t n = size_t(m.num_pixels);
  s.range_mm.resize(n);
  s.signal.resize(n);
  s.reflectivity.resize(n);
  for (size_t i = 0; i < n; ++i) {
    s.range_mm[i] = m.range_mm[i] < 0 ? 0u : uint32_t(m.range_mm[i]);
    s.signal[i] = uint16_t(std::max<int16_t>(m.signal[i], 0));
    s.reflectivity[i] = m.reflectivity[i];
  }
  s.column_utime = m.column_utime;
  s.measurement_id.resize(m.width);
  s.column_valid.resize(m.width);
  for (int c = 0; c < m.width; ++c) {
    s.measurement_id[c] = uint16_t(m.measurement_id[c]);
    s.column_valid[c] = m.column_valid[c] ? 1 : 0;
  }
  auto& b = s.beams;
  b.altitude_deg.assign(m.beam_altitude_deg.begin(), m.beam_altitude_deg.end());
  b.azimuth_deg.assign(m.beam_azimuth_deg.begin(), m.beam_azimuth_deg.end());
  b.pixel_shift_by_row.assign(m.pixel_shift_by_row.begin(), m.pixel_shift_by_row.end());
  b.beam_offset_mm = m.lidar_origin_to_beam_origin_mm;
  std::copy(m.lidar_to_sensor, m.lidar_to_sensor + 16, b.lidar_to_sensor.begin());
  s.missing_columns = m.missing_columns;
  s.status = ScanStatus(m.status);
}

}  // namespace fploc::adapters
