// point_cloud2_t <-> rec::PointCloud2 (a ROS PointCloud2: field layout + point bytes). Pure mappings.
#pragma once
#include <fploc/point_cloud2_t.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "fploc/recording/ros_msgs.h"

namespace fploc::adapters {

// Everything but the point bytes (m.size = 0, m.data empty): the header `fploc import` encodes before
// appending the recording's bytes (see encode_without_data).
void to_msg_header(const rec::PointCloud2& c, int64_t seq, const std::string& source, point_cloud2_t& m);
// The whole message (the point bytes copied).
void to_msg(const rec::PointCloud2& c, int64_t seq, const std::string& source, point_cloud2_t& m);
// The bytes of to_msg(c, ...).encode() minus its last c.data_size bytes (the points): appending the
// points gives the encoded message, without copying them into a message first.
void encode_without_data(const rec::PointCloud2& c, int64_t seq, const std::string& source, std::vector<uint8_t>& out);
// A view of m as a PointCloud2 (c.data points into m.data: valid while m lives). False with *err when
// the message is inconsistent (a field's datatype out of range, negative sizes).
bool from_msg(const point_cloud2_t& m, rec::PointCloud2& c, std::string* err);

}  // namespace fploc::adapters
