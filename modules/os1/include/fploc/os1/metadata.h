// Ouster sensor metadata (the JSON the sensor returns from get_metadata / ouster-sdk writes next to a pcap).
// Three layouts are read: legacy flat keys (fw <= 2.1 "legacy" files), the nested layout (beam_intrinsics,
// lidar_data_format, config_params, ...), and the reduced file that carries only beam angles and
// lidar_mode. Missing optional fields take the Ouster SDK defaults (see default_data_format below) and are
// listed in SensorInfo::defaulted. Transport-free; no JSON types in this header.
#pragma once
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "fploc/os1/ports.h"
#include "fploc/core/scan.h"

namespace fploc::os1 {

// kRng15Rfl8Nir8: the low-data-rate profile (4-byte pixels: range in 8 mm units, 15 bits; reflectivity; NIR).
enum class UdpProfile { kLegacy = 0, kRng19Rfl8Sig16Nir16 = 1, kRng15Rfl8Nir8 = 2 };
const char* to_string(UdpProfile p);

struct SensorInfo {
  BeamIntrinsics beams;             // angles [deg], pixel_shift_by_row, beam offset [mm], lidar_to_sensor
  int columns_per_frame = 1024;     // W
  int pixels_per_column = 64;       // H (= beams.beams())
  int columns_per_packet = 16;
  int column_window_first = 0;      // azimuth window [first, last] in measurement ids (inclusive)
  int column_window_last = 1023;
  double frequency_hz = 10.0;       // from lidar_mode
  std::string lidar_mode = "1024x10";
  std::string prod_line;            // e.g. "OS-1-64" ("" when unknown)
  std::string serial;               // prod_sn
  std::string firmware;             // build_rev / image_rev
  UdpProfile profile = UdpProfile::kLegacy;
  int udp_port_lidar = kDefaultLidarPort;
  int udp_port_imu = kDefaultImuPort;
  // Row-major 4x4, translation in mm (SDK default for OS-1 when absent).
  std::array<double, 16> imu_to_sensor{1, 0, 0, 6.253, 0, 1, 0, -11.775, 0, 0, 1, 7.645, 0, 0, 0, 1};
  std::vector<std::string> defaulted;  // fields that were absent and took a default (for logs)

  // Columns inside the azimuth window (what a complete frame holds).
  int window_columns() const;
  bool in_window(int measurement_id) const;
  // "OS-1-64 sn 991913000010" (or "OS-1 (64 beams)" when the file does not say).
  std::string sensor_name() const;
};

// Thrown for unreadable files, malformed JSON, missing required fields (beam angles) and inconsistent
// values (beam counts, lidar_mode vs columns_per_frame). The message names the file and the field.
struct MetadataError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

SensorInfo load_metadata(const std::string& path);
// `source` names the input in error messages (usually the path).
SensorInfo parse_metadata(const std::string& json_text, const std::string& source = "<metadata>");

// Ouster SDK defaults for a lidar_mode ("1024x10") and beam count: 16 columns per packet,
// pixel_shift_by_row {3s,2s,s,0} repeated with s = 3 (512), 6 (1024), 12 (2048) columns, beam offset 12.163 mm
// (gen-1 OS-1) unless prod_line says otherwise (OS-0 27.67, OS-1 15.806, OS-2 13.762 as in the SDK).
std::vector<int> default_pixel_shift(int beams, int columns_per_frame);
double default_beam_offset_mm(const std::string& prod_line);
// Parses "WxF"; throws MetadataError for anything else.
void parse_lidar_mode(const std::string& mode, int& columns, double& hz, const std::string& source);

// Writes `info` as a legacy flat metadata file (plus udp_profile_lidar and the ports) that
// parse_metadata reads back to the same SensorInfo (the simulator ships this next to its captures).
std::string metadata_to_json(const SensorInfo& info);

// A synthetic SensorInfo (simulator, tests): beams with the given angles, lidar_mode, SDK defaults.
SensorInfo make_sensor_info(const std::vector<double>& altitude_deg, const std::vector<double>& azimuth_deg,
                            const std::string& lidar_mode = "1024x10", UdpProfile profile = UdpProfile::kLegacy);

}  // namespace fploc::os1
