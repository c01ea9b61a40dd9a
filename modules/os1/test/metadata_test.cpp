#include "fploc/os1/metadata.h"

#include <gtest/gtest.h>

#include "test_util.h"

using namespace fploc::os1;
using fploc::os1::test::ouster_dir;

TEST(Metadata, ReducedFileTakesDefaults) {
  FPLOC_REQUIRE_SHARED();
  auto info = load_metadata(ouster_dir() + "/OS-1-64_sensor_config_reduced.json");
  EXPECT_EQ(info.pixels_per_column, 64);
  EXPECT_EQ(info.beams.beams(), 64);
  EXPECT_EQ(info.columns_per_frame, 1024);
  EXPECT_EQ(info.columns_per_packet, 16);
  EXPECT_DOUBLE_EQ(info.frequency_hz, 10.0);
  EXPECT_DOUBLE_EQ(info.beams.beam_offset_mm, 12.163);
  ASSERT_EQ(info.beams.pixel_shift_by_row.size(), 64u);
  EXPECT_EQ(info.beams.pixel_shift_by_row[0], 18);
  EXPECT_EQ(info.beams.pixel_shift_by_row[3], 0);
  EXPECT_EQ(info.beams.pixel_shift_by_row[4], 18);
  EXPECT_DOUBLE_EQ(info.beams.altitude_deg[0], 16.46);
  EXPECT_DOUBLE_EQ(info.beams.lidar_to_sensor[11], 36.18);
  EXPECT_EQ(info.profile, UdpProfile::kLegacy);
  EXPECT_FALSE(info.defaulted.empty());
}

TEST(Metadata, LegacyFlatAndNestedAgree) {
  FPLOC_REQUIRE_SHARED();
  auto flat = load_metadata(ouster_dir() + "/metadata/2_1_2_os1-991913000010-64_legacy.json");
  auto nested = load_metadata(ouster_dir() + "/metadata/2_1_2_os1-991913000010-64.json");
  EXPECT_EQ(flat.beams.altitude_deg, nested.beams.altitude_deg);
  EXPECT_EQ(flat.beams.azimuth_deg, nested.beams.azimuth_deg);
  EXPECT_EQ(flat.beams.pixel_shift_by_row, nested.beams.pixel_shift_by_row);
  EXPECT_EQ(flat.beams.pixel_shift_by_row[0], 19);
  EXPECT_DOUBLE_EQ(flat.beams.beam_offset_mm, 12.163);
  EXPECT_DOUBLE_EQ(nested.beams.beam_offset_mm, 12.163);
  EXPECT_EQ(flat.prod_line, "OS-1-64");
  EXPECT_EQ(nested.serial, flat.serial);
  EXPECT_FALSE(nested.serial.empty());
}

TEST(Metadata, AllSharedFilesLoad) {
  FPLOC_REQUIRE_SHARED();
  struct C { const char* f; int beams; int cols; UdpProfile p; int first, last; };
  for (C c : {C{"/OS-1-32-G_v2.1.1_1024x10.json", 32, 1024, UdpProfile::kLegacy, 0, 1023},
              C{"/OS-2-32-U0_v2.0.0_1024x10.json", 32, 1024, UdpProfile::kLegacy, 0, 1023},
              C{"/same_ports_legacy.1.json", 128, 1024, UdpProfile::kLegacy, 0, 1023},
              C{"/same_ports_legacy.2.json", 64, 1024, UdpProfile::kLegacy, 0, 1023},
              C{"/metadata/1_12_os1-991913000010-64.json", 64, 1024, UdpProfile::kLegacy, 0, 1023},
              C{"/metadata/2_5_0_os-992146000760-128.json", 128, 1024, UdpProfile::kRng19Rfl8Sig16Nir16, 912, 1022}}) {
    SCOPED_TRACE(c.f);
    auto info = load_metadata(ouster_dir() + c.f);
    EXPECT_EQ(info.pixels_per_column, c.beams);
    EXPECT_EQ(info.columns_per_frame, c.cols);
    EXPECT_EQ(info.profile, c.p);
    EXPECT_EQ(info.column_window_first, c.first);
    EXPECT_EQ(info.column_window_last, c.last);
    EXPECT_EQ(int(info.beams.pixel_shift_by_row.size()), c.beams);
  }
  auto g = load_metadata(ouster_dir() + "/OS-1-32-G_v2.1.1_1024x10.json");
  EXPECT_DOUBLE_EQ(g.beams.beam_offset_mm, 15.806);
  EXPECT_DOUBLE_EQ(g.imu_to_sensor[3], 6.253);
  EXPECT_EQ(g.prod_line, "OS-1-32-G");
}

static std::string error_of(const std::string& text) {
  try {
    parse_metadata(text, "test.json");
  } catch (const MetadataError& e) {
    return e.what();
  }
  return "";
}

TEST(Metadata, ErrorsNameFileAndField) {
  EXPECT_NE(error_of("{").find("test.json"), std::string::npos);
  EXPECT_NE(error_of("[1,2]").find("not a JSON object"), std::string::npos);
  // Found by fuzz_metadata: a number out of double range made nlohmann throw out_of_range.
  EXPECT_NE(error_of(R"({"beam_altitude_angles": [1e999]})").find("not valid JSON"), std::string::npos);
  auto e = error_of(R"({"beam_azimuth_angles": [0, 0]})");
  EXPECT_NE(e.find("beam_altitude_angles"), std::string::npos) << e;
  e = error_of(R"({"beam_altitude_angles": [1, 2, 3], "beam_azimuth_angles": [0, 0]})");
  EXPECT_NE(e.find("beam_azimuth_angles"), std::string::npos) << e;
  EXPECT_NE(e.find("3"), std::string::npos) << e;
  e = error_of(R"({"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0],
                  "data_format": {"pixels_per_column": 64}})");
  EXPECT_NE(e.find("pixels_per_column"), std::string::npos) << e;
  e = error_of(R"({"beam_altitude_angles": [1, "x"], "beam_azimuth_angles": [0, 0]})");
  EXPECT_NE(e.find("element 1"), std::string::npos) << e;
  e = error_of(R"({"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0], "lidar_mode": "1000x7"})");
  EXPECT_NE(e.find("lidar_mode"), std::string::npos) << e;
  e = error_of(R"({"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0], "lidar_mode": "512x10",
                  "lidar_data_format": {"columns_per_frame": 1024}})");
  EXPECT_NE(e.find("columns_per_frame"), std::string::npos) << e;
  e = error_of(R"({"beam_intrinsics": {"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0]},
                  "lidar_data_format": {"pixel_shift_by_row": [1, 2, 3]}})");
  EXPECT_NE(e.find("pixel_shift_by_row"), std::string::npos) << e;
  e = error_of(R"({"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0], "lidar_to_sensor_transform": [1, 0]})");
  EXPECT_NE(e.find("lidar_to_sensor_transform"), std::string::npos) << e;
  EXPECT_THROW(load_metadata("/nonexistent/meta.json"), MetadataError);
  EXPECT_EQ(error_of(R"({"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0]})"), "");
}

TEST(Metadata, DefaultPixelShift) {
  EXPECT_EQ(default_pixel_shift(4, 512), (std::vector<int>{9, 6, 3, 0}));
  EXPECT_EQ(default_pixel_shift(8, 2048), (std::vector<int>{36, 24, 12, 0, 36, 24, 12, 0}));
}

TEST(Metadata, WriteReadRoundTrip) {
  SensorInfo a = make_sensor_info({10.5, 0.25, -3.0, -12.125}, {3.1, -1.0, 0.5, -3.1}, "2048x10",
                                  UdpProfile::kRng19Rfl8Sig16Nir16);
  a.prod_line = "OS-1-4-test";
  a.serial = "42";
  a.beams.beam_offset_mm = 15.806;
  a.beams.lidar_to_sensor[11] = 38.195;
  a.imu_to_sensor[3] = 1.5;
  a.column_window_first = 100, a.column_window_last = 50;
  a.udp_port_lidar = 17502;
  const SensorInfo b = parse_metadata(metadata_to_json(a), "roundtrip");
  EXPECT_EQ(b.beams.altitude_deg, a.beams.altitude_deg);
  EXPECT_EQ(b.beams.azimuth_deg, a.beams.azimuth_deg);
  EXPECT_EQ(b.beams.pixel_shift_by_row, a.beams.pixel_shift_by_row);
  EXPECT_EQ(b.beams.lidar_to_sensor, a.beams.lidar_to_sensor);
  EXPECT_EQ(b.imu_to_sensor, a.imu_to_sensor);
  EXPECT_DOUBLE_EQ(b.beams.beam_offset_mm, 15.806);
  EXPECT_EQ(b.columns_per_frame, 2048);
  EXPECT_EQ(b.profile, UdpProfile::kRng19Rfl8Sig16Nir16);
  EXPECT_EQ(b.column_window_first, 100);
  EXPECT_EQ(b.column_window_last, 50);
  EXPECT_EQ(b.window_columns(), 2048 - 100 + 51);
  EXPECT_TRUE(b.in_window(2000) && b.in_window(0) && !b.in_window(75));
  EXPECT_EQ(b.udp_port_lidar, 17502);
  EXPECT_EQ(b.sensor_name(), "OS-1-4-test sn 42");
  EXPECT_TRUE(b.defaulted.empty()) << b.defaulted.front();
}
