#include "fploc/sim/sensor.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "fploc/sim/rng.h"

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
  auto fail = [&](const std::string& m) {
    if (error) *error = path + ": " + m;
    return false;
  };
  std::ifstream in(path);
  if (!in) return fail("cannot open");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    return fail(std::string("not JSON: ") + e.what());
  }
  auto find = [&](const char* key, const char* nested) -> const nlohmann::json* {
    if (j.contains(key)) return &j[key];
    if (nested && j.contains(nested) && j[nested].contains(key)) return &j[nested][key];
    return nullptr;
  };
  BeamIntrinsics b;
  const auto* alt = find("beam_altitude_angles", "beam_intrinsics");
  const auto* az = find("beam_azimuth_angles", "beam_intrinsics");
  if (!alt || !alt->is_array()) return fail("missing field beam_altitude_angles");
  if (!az || !az->is_array()) return fail("missing field beam_azimuth_angles");
  if (alt->size() != az->size() || alt->empty()) return fail("beam_altitude_angles and beam_azimuth_angles differ in size");
  try {
    for (const auto& v : *alt) b.altitude_deg.push_back(v.get<double>());
    for (const auto& v : *az) b.azimuth_deg.push_back(v.get<double>());
    if (const auto* off = find("lidar_origin_to_beam_origin_mm", "beam_intrinsics")) b.beam_offset_mm = off->get<double>();
    else b.beam_offset_mm = 12.163;
    if (const auto* t = find("lidar_to_sensor_transform", "lidar_intrinsics"); t && t->is_array() && t->size() == 16)
      for (int i = 0; i < 16; ++i) b.lidar_to_sensor[size_t(i)] = (*t)[size_t(i)].get<double>();
    const nlohmann::json* df = find("data_format", nullptr);
    if (!df) df = find("lidar_data_format", nullptr);
    if (df && df->contains("pixel_shift_by_row"))
      for (const auto& v : (*df)["pixel_shift_by_row"]) b.pixel_shift_by_row.push_back(v.get<int>());
  } catch (const std::exception& e) {
    return fail(std::string("bad value: ") + e.what());
  }
  if (b.pixel_shift_by_row.size() != b.altitude_deg.size()) {
    b.pixel_shift_by_row.clear();
    const int s4[4] = {18, 12, 6, 0};
    for (size_t u = 0; u < b.altitude_deg.size(); ++u) b.pixel_shift_by_row.push_back(s4[u % 4]);
  }
  out = std::move(b);
  return true;
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
