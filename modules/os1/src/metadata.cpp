#include "fploc/os1/metadata.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace fploc::os1 {
namespace {

using json = nlohmann::json;

// Sections of the nested (non-legacy) layout, searched after the top level.
const char* const kSections[] = {"beam_intrinsics", "lidar_intrinsics", "imu_intrinsics", "lidar_data_format",
                                 "config_params",   "sensor_info",      "data_format"};

struct Reader {
  const json& root;
  std::string source;

  // Returns the value and its dotted path, or nullptr. Sections that are not objects (fw 1.12 writes
  // "error: Command not recognized." for lidar_data_format) are skipped.
  const json* find(const std::string& key, std::string* where = nullptr) const {
    if (root.contains(key)) {
      if (where) *where = key;
      return &root[key];
    }
    for (const char* s : kSections) {
      auto it = root.find(s);
      if (it != root.end() && it->is_object() && it->contains(key)) {
        if (where) *where = std::string(s) + "." + key;
        return &(*it)[key];
      }
    }
    return nullptr;
  }
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw MetadataError(source + ": field '" + field + "': " + what);
  }
  std::vector<double> numbers(const std::string& key, bool required, bool* found = nullptr) const {
    std::string where = key;
    const json* v = find(key, &where);
    if (found) *found = v != nullptr;
    if (!v) {
      if (required) throw MetadataError(source + ": missing required field '" + key + "'");
      return {};
    }
    if (!v->is_array()) fail(where, "expected an array of numbers");
    std::vector<double> out;
    out.reserve(v->size());
    for (size_t i = 0; i < v->size(); ++i) {
      const json& e = (*v)[i];
      if (!e.is_number()) fail(where, "element " + std::to_string(i) + " is not a number");
      const double d = e.get<double>();
      if (!std::isfinite(d)) fail(where, "element " + std::to_string(i) + " is not finite");
      out.push_back(d);
    }
    return out;
  }
  bool number(const std::string& key, double& out) const {
    std::string where = key;
    const json* v = find(key, &where);
    if (!v) return false;
    if (!v->is_number()) fail(where, "expected a number");
    out = v->get<double>();
    if (!std::isfinite(out)) fail(where, "not finite");
    return true;
  }
  bool integer(const std::string& key, int& out, int lo, int hi) const {
    std::string where = key;
    const json* v = find(key, &where);
    if (!v) return false;
    if (!v->is_number_integer()) fail(where, "expected an integer");
    const long long x = v->get<long long>();
    if (x < lo || x > hi) fail(where, "value " + std::to_string(x) + " outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    out = int(x);
    return true;
  }
  bool string(const std::string& key, std::string& out) const {
    std::string where = key;
    const json* v = find(key, &where);
    if (!v || v->is_null()) return false;
    if (v->is_string()) {
      out = v->get<std::string>();
      return true;
    }
    if (v->is_number_integer()) {  // prod_sn is a number in some files
      out = std::to_string(v->get<long long>());
      return true;
    }
    fail(where, "expected a string");
  }
};

std::array<double, 16> matrix(const Reader& r, const std::string& key, const std::array<double, 16>& def,
                              std::vector<std::string>& defaulted) {
  bool found = false;
  auto v = r.numbers(key, false, &found);
  if (!found) {
    defaulted.push_back(key);
    return def;
  }
  if (v.size() != 16) r.fail(key, "expected 16 values (row-major 4x4), got " + std::to_string(v.size()));
  std::array<double, 16> m;
  for (int i = 0; i < 16; ++i) m[i] = v[i];
  return m;
}

}  // namespace

const char* to_string(UdpProfile p) {
  switch (p) {
    case UdpProfile::kLegacy: return "LEGACY";
    case UdpProfile::kRng19Rfl8Sig16Nir16: return "RNG19_RFL8_SIG16_NIR16";
    case UdpProfile::kRng15Rfl8Nir8: return "RNG15_RFL8_NIR8";
  }
  return "?";
}

int SensorInfo::window_columns() const {
  if (column_window_first <= column_window_last) return column_window_last - column_window_first + 1;
  return columns_per_frame - column_window_first + column_window_last + 1;  // wraps around 0
}

bool SensorInfo::in_window(int m) const {
  if (column_window_first <= column_window_last) return m >= column_window_first && m <= column_window_last;
  return m >= column_window_first || m <= column_window_last;
}

std::string SensorInfo::sensor_name() const {
  std::string s = prod_line.empty() ? "OS-1 (" + std::to_string(pixels_per_column) + " beams)" : prod_line;
  if (!serial.empty()) s += " sn " + serial;
  return s;
}

void parse_lidar_mode(const std::string& mode, int& columns, double& hz, const std::string& source) {
  int w = 0, f = 0;
  char x = 0;
  std::istringstream is(mode);
  if (!(is >> w >> x >> f) || x != 'x' || !is.eof() ||
      !(w == 512 || w == 1024 || w == 2048 || w == 4096) || !(f == 5 || f == 10 || f == 20))
    throw MetadataError(source + ": field 'lidar_mode': unsupported value '" + mode +
                        "' (expected 512x10, 512x20, 1024x10, 1024x20, 2048x10, 4096x5)");
  columns = w;
  hz = f;
}

std::vector<int> default_pixel_shift(int beams, int columns_per_frame) {
  const int s = columns_per_frame == 512 ? 3 : columns_per_frame == 1024 ? 6 : columns_per_frame == 2048 ? 12 : 0;
  std::vector<int> out(size_t(std::max(beams, 0)));
  for (int i = 0; i < beams; ++i) out[i] = s * (3 - i % 4);
  return out;
}

double default_beam_offset_mm(const std::string& prod_line) {
  // Gen-1 OS-1 (prod_line "OS-1-16/32/64" without a suffix, or unknown): 12.163 mm.
  if (prod_line.rfind("OS-0-", 0) == 0) return 27.67;
  if (prod_line.rfind("OS-2-", 0) == 0) return 13.762;
  if (prod_line.rfind("OS-1-", 0) == 0 && prod_line.find('-', 5) != std::string::npos) return 15.806;
  return 12.163;
}

SensorInfo parse_metadata(const std::string& text, const std::string& source) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for numbers like 1e999
    throw MetadataError(source + ": not valid JSON (" + e.what() + ")");
  }
  if (!root.is_object()) throw MetadataError(source + ": top level is not a JSON object");
  Reader r{root, source};
  SensorInfo info;
  auto& d = info.defaulted;

  info.beams.altitude_deg = r.numbers("beam_altitude_angles", true);
  info.beams.azimuth_deg = r.numbers("beam_azimuth_angles", true);
  const int beams = int(info.beams.altitude_deg.size());
  if (beams == 0) r.fail("beam_altitude_angles", "empty");
  if (int(info.beams.azimuth_deg.size()) != beams)
    r.fail("beam_azimuth_angles", "has " + std::to_string(info.beams.azimuth_deg.size()) +
                                      " values but beam_altitude_angles has " + std::to_string(beams));

  r.string("prod_line", info.prod_line) || (d.push_back("prod_line"), true);
  r.string("prod_sn", info.serial);
  if (!r.string("build_rev", info.firmware)) r.string("image_rev", info.firmware);

  if (!r.string("lidar_mode", info.lidar_mode)) d.push_back("lidar_mode");
  parse_lidar_mode(info.lidar_mode, info.columns_per_frame, info.frequency_hz, source);
  const int mode_cols = info.columns_per_frame;

  if (!r.integer("columns_per_frame", info.columns_per_frame, 1, 65535)) d.push_back("columns_per_frame");
  if (info.columns_per_frame != mode_cols)
    r.fail("columns_per_frame", std::to_string(info.columns_per_frame) + " does not match lidar_mode '" +
                                    info.lidar_mode + "'");
  info.pixels_per_column = beams;
  if (!r.integer("pixels_per_column", info.pixels_per_column, 1, 1024)) d.push_back("pixels_per_column");
  if (info.pixels_per_column != beams)
    r.fail("pixels_per_column", std::to_string(info.pixels_per_column) + " but the file has " +
                                    std::to_string(beams) + " beam angles");
  if (!r.integer("columns_per_packet", info.columns_per_packet, 1, 64)) d.push_back("columns_per_packet");

  bool found = false;
  auto shift = r.numbers("pixel_shift_by_row", false, &found);
  if (found) {
    if (int(shift.size()) != beams)
      r.fail("pixel_shift_by_row", "has " + std::to_string(shift.size()) + " values for " + std::to_string(beams) + " beams");
    info.beams.pixel_shift_by_row.clear();
    for (double s : shift) {
      if (s != std::floor(s) || std::abs(s) >= info.columns_per_frame) r.fail("pixel_shift_by_row", "bad shift " + std::to_string(s));
      info.beams.pixel_shift_by_row.push_back(int(s));
    }
  } else {
    d.push_back("pixel_shift_by_row");
    info.beams.pixel_shift_by_row = default_pixel_shift(beams, info.columns_per_frame);
  }

  auto window = r.numbers("column_window", false, &found);
  info.column_window_first = 0;
  info.column_window_last = info.columns_per_frame - 1;
  if (found) {
    if (window.size() != 2 || window[0] < 0 || window[1] < 0 || window[0] >= info.columns_per_frame ||
        window[1] >= info.columns_per_frame)
      r.fail("column_window", "expected [first, last] within 0.." + std::to_string(info.columns_per_frame - 1));
    info.column_window_first = int(window[0]);
    info.column_window_last = int(window[1]);
  } else {
    d.push_back("column_window");
  }

  if (!r.number("lidar_origin_to_beam_origin_mm", info.beams.beam_offset_mm)) {
    d.push_back("lidar_origin_to_beam_origin_mm");
    info.beams.beam_offset_mm = default_beam_offset_mm(info.prod_line);
  }
  info.beams.lidar_to_sensor = matrix(r, "lidar_to_sensor_transform", BeamIntrinsics{}.lidar_to_sensor, d);
  info.imu_to_sensor = matrix(r, "imu_to_sensor_transform", SensorInfo{}.imu_to_sensor, d);

  std::string profile;
  if (r.string("udp_profile_lidar", profile)) {
    if (profile == "LEGACY") info.profile = UdpProfile::kLegacy;
    else if (profile == "RNG19_RFL8_SIG16_NIR16") info.profile = UdpProfile::kRng19Rfl8Sig16Nir16;
    else if (profile == "RNG15_RFL8_NIR8") info.profile = UdpProfile::kRng15Rfl8Nir8;
    else r.fail("udp_profile_lidar", "unsupported profile '" + profile + "' (LEGACY, RNG19_RFL8_SIG16_NIR16, RNG15_RFL8_NIR8)");
  } else {
    d.push_back("udp_profile_lidar");
  }
  r.integer("udp_port_lidar", info.udp_port_lidar, 0, 65535);
  r.integer("udp_port_imu", info.udp_port_imu, 0, 65535);
  return info;
}

SensorInfo load_metadata(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw MetadataError(path + ": cannot open metadata file");
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_metadata(ss.str(), path);
}

std::string metadata_to_json(const SensorInfo& info) {
  json j;
  j["beam_altitude_angles"] = info.beams.altitude_deg;
  j["beam_azimuth_angles"] = info.beams.azimuth_deg;
  j["lidar_origin_to_beam_origin_mm"] = info.beams.beam_offset_mm;
  j["lidar_to_sensor_transform"] = info.beams.lidar_to_sensor;
  j["imu_to_sensor_transform"] = info.imu_to_sensor;
  j["lidar_mode"] = info.lidar_mode;
  if (!info.prod_line.empty()) j["prod_line"] = info.prod_line;
  if (!info.serial.empty()) j["prod_sn"] = info.serial;
  if (!info.firmware.empty()) j["build_rev"] = info.firmware;
  j["udp_profile_lidar"] = to_string(info.profile);
  j["udp_port_lidar"] = info.udp_port_lidar;
  j["udp_port_imu"] = info.udp_port_imu;
  j["data_format"] = {{"pixels_per_column", info.pixels_per_column},
                      {"columns_per_packet", info.columns_per_packet},
                      {"columns_per_frame", info.columns_per_frame},
                      {"pixel_shift_by_row", info.beams.pixel_shift_by_row},
                      {"column_window", {info.column_window_first, info.column_window_last}}};
  return j.dump(4);
}

SensorInfo make_sensor_info(const std::vector<double>& altitude_deg, const std::vector<double>& azimuth_deg,
                            const std::string& lidar_mode, UdpProfile profile) {
  if (altitude_deg.size() != azimuth_deg.size() || altitude_deg.empty())
    throw MetadataError("make_sensor_info: altitude and azimuth angle counts differ or are empty");
  SensorInfo info;
  info.beams.altitude_deg = altitude_deg;
  info.beams.azimuth_deg = azimuth_deg;
  info.lidar_mode = lidar_mode;
  parse_lidar_mode(lidar_mode, info.columns_per_frame, info.frequency_hz, "make_sensor_info");
  info.pixels_per_column = int(altitude_deg.size());
  info.beams.pixel_shift_by_row = default_pixel_shift(info.pixels_per_column, info.columns_per_frame);
  info.beams.beam_offset_mm = default_beam_offset_mm("");
  info.column_window_first = 0;
  info.column_window_last = info.columns_per_frame - 1;
  info.profile = profile;
  return info;
}

}  // namespace fploc::os1
