#include "fploc/os1/sensor_http.h"

#include <httplib.h>

#include <cmath>

namespace fploc::os1 {

bool fetch_sensor_metadata(const std::string& host, double timeout_s, std::string* json, std::string* error) {
  std::string name = host;
  int port = 80;
  if (const auto colon = host.rfind(':'); colon != std::string::npos && host.find(']') == std::string::npos) {
    name = host.substr(0, colon);
    try {
      port = std::stoi(host.substr(colon + 1));
    } catch (const std::exception&) {
      port = -1;
    }
    if (port <= 0 || port > 65535) {
      *error = "sensor_hostname '" + host + "': bad port";
      return false;
    }
  }
  httplib::Client cli(name, port);
  const auto sec = time_t(timeout_s), usec = time_t(std::fmod(timeout_s, 1.0) * 1e6);
  cli.set_connection_timeout(sec, usec);
  cli.set_read_timeout(sec + 2, usec);
  const std::string url = "http://" + host + kMetadataPath;
  auto res = cli.Get(kMetadataPath);
  if (!res) {
    *error = url + ": no answer (" + httplib::to_string(res.error()) + " error)";
    return false;
  }
  if (res->status != 200) {
    *error = url + ": HTTP " + std::to_string(res->status);
    return false;
  }
  *json = res->body;
  return true;
}

}  // namespace fploc::os1
