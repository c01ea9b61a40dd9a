#include "fploc/sim/sensor.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "fploc/core/rng.h"

namespace fploc::sim {

BeamIntrinsics nominal_os1_64() {
  BeamIntrinsics b;
  const int n = 64;
  const double az[4] = {3.1, 0.9, -1.3, -3.4};
  const int shift[4] = {19, 13, 6, 0};
  for (int u = 0; u < n; ++u) {
    b.altitude_deg.push_back(16.6 - u * (33.2 / (n - 1)));
    b.azimuth_deg.push_back(az[u % 4]);
    b.pixel_shift_by_row.push_back(shift[u % 4]);
  }
  b.beam_offset_mm = 12.163;
  return b;
}

bool load_beam_intrinsics_json(const std::string& path, BeamIntrinsics& out, std::string* error) {
  // The OS-1 driver's metadata reader (legacy flat, nested and reduced layouts; SDK defaults).
  try {
    out = os1::load_metadata(path).beams;
    return true;
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return false;
  }
}

os1::SensorInfo sensor_info_for(const BeamIntrinsics& beams, int width, double rate_hz) {
  std::vector<double> alt = beams.altitude_deg, az = beams.azimuth_deg;
  os1::SensorInfo info = os1::make_sensor_info(alt, az, std::to_string(width) + "x" + std::to_string(int(std::lround(rate_hz))));
  info.beams = beams;
  info.prod_line = "OS-1-" + std::to_string(beams.beams());
  info.serial = "sim";
  return info;
}

std::string metadata_json(const os1::SensorInfo& info) {
  nlohmann::json j;
  j["beam_altitude_angles"] = info.beams.altitude_deg;
  j["beam_azimuth_angles"] = info.beams.azimuth_deg;
  j["lidar_origin_to_beam_origin_mm"] = info.beams.beam_offset_mm;
  j["lidar_to_sensor_transform"] = std::vector<double>(info.beams.lidar_to_sensor.begin(), info.beams.lidar_to_sensor.end());
  j["imu_to_sensor_transform"] = std::vector<double>(info.imu_to_sensor.begin(), info.imu_to_sensor.end());
  j["lidar_mode"] = info.lidar_mode;
  j["prod_line"] = info.prod_line;
  j["prod_sn"] = info.serial;
  j["data_format"] = {{"pixels_per_column", info.pixels_per_column},
                      {"columns_per_packet", info.columns_per_packet},
                      {"columns_per_frame", info.columns_per_frame},
                      {"pixel_shift_by_row", info.beams.pixel_shift_by_row},
                      {"column_window", {info.column_window_first, info.column_window_last}}};
  return j.dump(1);
}

BeamIntrinsics default_beams(const std::string& shared_dir, std::string* source) {
  const std::string p = shared_dir + "/data/ouster/metadata/2_1_2_os1-991913000010-64_legacy.json";
  BeamIntrinsics b;
  std::string err;
  if (std::filesystem::exists(p) && load_beam_intrinsics_json(p, b, &err)) {
    if (source) *source = p;
    return b;
  }
  if (source) *source = "nominal OS-1-64 (generated in code; " + (err.empty() ? p + " not found" : err) + ")";
  return nominal_os1_64();
}

LidarSim::LidarSim(SensorConfig cfg) : cfg_(std::move(cfg)) { lut_ = make_xyz_lut(cfg_.beams, cfg_.width); }

void LidarSim::simulate(World& world, const PoseFn& pose, double t0, int64_t frame_index, uint64_t seed,
                        SimScan& out) const {
  const int H = cfg_.beams.beams(), W = cfg_.width;
  Scan& s = out.scan;
  s.resize(H, W);
  s.beams = cfg_.beams;
  s.sensor = "sim OS-1-" + std::to_string(H);
  s.seq = frame_index;
  s.frame_id = int32_t(frame_index & 0xFFFF);
  s.utime = int64_t(std::llround(t0 * 1e6));
  s.missing_columns = 0;
  s.status = ScanStatus::kOk;
  out.label.assign(size_t(H) * W, uint8_t(Label::kNone));
  out.element.assign(size_t(H) * W, -1);
  out.true_range_m.assign(size_t(H) * W, 0.f);
  const double dt_col = 1.0 / (cfg_.rate_hz * W);
  const double cos_graze = std::cos(cfg_.grazing_dropout_deg * M_PI / 180.0);
  Rng rng(mix_seed(seed, 0x5CA1, uint64_t(frame_index)));
  for (int v = 0; v < W; ++v) {
    const double tc = t0 + v * dt_col;
    s.column_utime[size_t(v)] = int64_t(std::llround(tc * 1e6));
    const Eigen::Isometry3d T = pose(tc);
    if (v == 0) out.gt = StampedPose::from(tc, T);
    world.set_time(tc);
    const Eigen::Matrix3d R = T.linear();
    const Eigen::Vector3d tr = T.translation();
    for (int u = 0; u < H; ++u) {
      const size_t i = size_t(u) * W + v;
      // Pixel ray in the sensor frame: point = offset + r * dir (r in mm, dir scaled by 1e-3).
      const Eigen::Vector3d dir = lut_.direction.row(long(i)).transpose().cast<double>() * 1e3;
      const Eigen::Vector3d off = lut_.offset.row(long(i)).transpose().cast<double>();
      const double dn = dir.norm();
      const Eigen::Vector3d dw = R * (dir / dn);
      const Eigen::Vector3d ow = R * off + tr;
      const Hit h = world.cast(ow, dw, cfg_.max_range_m * dn);
      // Draw noise for every pixel so the random stream does not depend on the scene.
      const double noise = rng.normal(cfg_.range_noise_m);
      const double drop = rng.uniform();
      if (h.label == Label::kNone) continue;
      const double r_true = h.t / dn;  // metres of Ouster range
      out.true_range_m[i] = float(r_true);
      const double cosi = std::abs(h.normal.dot(dw));
      if (drop < cfg_.dropout || cosi < cos_graze) continue;
      const double r = r_true + noise;
      if (r < cfg_.min_range_m || r > cfg_.max_range_m) continue;
      const uint32_t r_mm = uint32_t(std::llround(r * 1000.0)) & 0xFFFFFu;
      if (r_mm == 0) continue;
      s.range_mm[i] = r_mm;
      out.label[i] = uint8_t(h.label);
      out.element[i] = h.element;
      s.reflectivity[i] = h.reflectivity;
      const double sig = 4000.0 * h.reflectivity / 50.0 * std::max(cosi, 0.05) / std::max(1.0, r * r) + 20;
      s.signal[i] = uint16_t(std::min(sig, 65535.0));
    }
  }
}

}  // namespace fploc::sim
