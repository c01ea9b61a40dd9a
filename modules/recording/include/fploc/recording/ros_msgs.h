// Decoders for the ROS message types fploc imports, from ROS 1 serialization or ROS 2 CDR (the two
// differ only in alignment, string terminators and std_msgs/Header's seq). Each returns false with
// *err naming the field when the bytes do not hold the message; nothing throws.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/recording/recording.h"

namespace fploc::rec {

struct Header {
  int64_t stamp_ns = 0;
  std::string frame_id;
};

struct PointField {
  std::string name;
  uint32_t offset = 0;
  uint8_t datatype = 0;  // 1 INT8 2 UINT8 3 INT16 4 UINT16 5 INT32 6 UINT32 7 FLOAT32 8 FLOAT64
  uint32_t count = 1;
};

struct PointCloud2 {
  Header header;
  uint32_t height = 0, width = 0;
  std::vector<PointField> fields;
  bool is_bigendian = false;
  uint32_t point_step = 0, row_step = 0;
  const uint8_t* data = nullptr;  // points into the message bytes
  size_t data_size = 0;
  bool is_dense = false;
};

struct Imu {
  Header header;
  std::array<double, 4> orientation{};  // x y z w
  std::array<double, 3> angular_velocity{};
  std::array<double, 3> linear_acceleration{};
};

struct LaserScan {
  Header header;
  float angle_min = 0, angle_max = 0, angle_increment = 0, time_increment = 0, scan_time = 0, range_min = 0, range_max = 0;
  std::vector<float> ranges, intensities;
};

// The same message without copying its arrays: ranges and intensities point into the message bytes
// (4-byte floats in the message's byte order; big_endian only for big-endian CDR). What an importer
// that re-encodes the scan in one pass reads (decode(LaserScan) is this plus the copy).
struct LaserScanView {
  Header header;
  float angle_min = 0, angle_max = 0, angle_increment = 0, time_increment = 0, scan_time = 0, range_min = 0, range_max = 0;
  uint32_t num_ranges = 0, num_intensities = 0;
  const uint8_t* ranges = nullptr;
  const uint8_t* intensities = nullptr;
  bool big_endian = false;
};

struct Transform {
  Header header;
  std::string child_frame_id;
  std::array<double, 3> t{};
  std::array<double, 4> q{0, 0, 0, 1};  // x y z w
};

struct Odometry {
  Transform pose;  // header.frame_id -> child_frame_id
};

bool decode(const uint8_t* d, size_t n, Encoding e, PointCloud2& out, std::string* err);
bool decode(const uint8_t* d, size_t n, Encoding e, Imu& out, std::string* err);
bool decode(const uint8_t* d, size_t n, Encoding e, LaserScan& out, std::string* err);
bool decode(const uint8_t* d, size_t n, Encoding e, LaserScanView& out, std::string* err);
bool decode(const uint8_t* d, size_t n, Encoding e, Odometry& out, std::string* err);
bool decode_tf(const uint8_t* d, size_t n, Encoding e, std::vector<Transform>& out, std::string* err);
// uint8[] buf (ouster_ros/PacketMsg) and std_msgs/String.
bool decode_bytes(const uint8_t* d, size_t n, Encoding e, const uint8_t** data, size_t* size, std::string* err);
bool decode_string(const uint8_t* d, size_t n, Encoding e, std::string& out, std::string* err);

}  // namespace fploc::rec
