// The sensor's own HTTP API (Ouster firmware 2.x and later): GET http://HOST/api/v1/sensor/metadata
// returns the metadata JSON the driver needs (beam intrinsics, data format, lidar_mode), so a robot
// does not depend on a file copied from the sensor. cpp-httplib (Debian's libcpp-httplib-dev).
#pragma once
#include <string>

namespace fploc::os1 {

inline constexpr const char* kMetadataPath = "/api/v1/sensor/metadata";

// host: "os-122122000149.local", "169.254.56.220" or "127.0.0.1:8080". On success returns true and
// the body in *json; else false with *error naming the host and what failed (connection, HTTP status).
bool fetch_sensor_metadata(const std::string& host, double timeout_s, std::string* json, std::string* error);

}  // namespace fploc::os1
