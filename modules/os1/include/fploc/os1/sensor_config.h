// Configuring a live Ouster sensor over its HTTP API, the way the Ouster SDK's init_client / ouster_ros
// do it: read the firmware version, the active configuration, write the parameters that differ (UDP
// destination and ports, lidar mode, lidar packet profile, timestamp mode, operating mode), reinitialise,
// wait until the sensor reports RUNNING (or STANDBY when asked), re-read the metadata, and read its alerts.
// Firmware 2.1+ (HTTP API); 2.0 and 1.x (TCP API only) are refused with a clear error. No LCM.
// Endpoints (facts from the Ouster HTTP API reference and the SDK; see docs/notes/os1.md):
//   GET  /api/v1/system/firmware                         {"fw": "ousteros-image-prod-aries-v2.3.0+..."}
//   GET  /api/v1/sensor/metadata/sensor_info             status (fw 2.1: /api/v1/sensor/cmd/get_sensor_info)
//   fw 2.x: GET /api/v1/sensor/cmd/get_config_param?args=active|staged, set_config_param?args=.+<json>,
//           set_udp_dest_auto, reinitialize, save_config_params
//   fw 3+:  GET /api/v1/sensor/config, POST /api/v1/sensor/config?reinit=true&persist=false (JSON body)
//   GET  /api/v1/sensor/metadata (fw 2.1: assembled from the cmd/get_* endpoints)
//   GET  /api/v1/sensor/alerts[?cursor=N]                {"active": [...], "log": [...], "next_cursor": N}
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fploc::os1 {

// Every failure of the set-up; the message names the host and, where one is at fault, the parameter.
struct SensorConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct FirmwareVersion {
  int major = -1, minor = -1, patch = -1;
  std::string text;  // as the sensor reported it
  bool valid() const { return major >= 0; }
  bool at_least(int ma, int mi) const { return major > ma || (major == ma && minor >= mi); }
  std::string str() const;  // "v2.3.0"
};
// "ousteros-image-prod-aries-v2.3.0+20220415163956", "v3.0.1-rc.2", "2.1.2" -> 2.3.0 / 3.0.1 / 2.1.2.
FirmwareVersion parse_firmware_version(const std::string& s);

struct SensorAlert {
  std::string id;        // "0x01000017"
  std::string level;     // NOTICE, WARNING, ERROR
  std::string category;  // "UDP_TRANSMISSION", ...
  std::string msg, msg_verbose;
  bool active = false;
  int64_t cursor = -1;
  std::string text() const;  // "0x01000017 WARNING UDP_TRANSMISSION: msg (msg_verbose)"
};
struct AlertReport {
  std::vector<SensorAlert> active;  // all currently active alerts
  std::vector<SensorAlert> log;     // trigger / clear events since the asked cursor (at most 32 kept)
  int64_t next_cursor = 0;
};
// Throws SensorConfigError naming `source` on malformed JSON.
AlertReport parse_alerts(const std::string& json_text, const std::string& source);

// What to set; an empty string keeps the sensor's value.
struct SensorConfigRequest {
  // "" = this host's address on the route to the sensor (local_address_towards), "@auto" = the sensor
  // detects the address its HTTP request came from (the SDK's default), else an IP or host name.
  std::string udp_dest;
  int udp_port_lidar = 7502;           // 0 = keep
  int udp_port_imu = 7503;             // 0 = keep
  std::string lidar_mode;              // 512x10 512x20 1024x10 1024x20 2048x10 4096x5
  std::string udp_profile_lidar;       // LEGACY RNG19_RFL8_SIG16_NIR16 RNG15_RFL8_NIR8 (the ones fploc decodes)
  std::string timestamp_mode;          // TIME_FROM_INTERNAL_OSC TIME_FROM_SYNC_PULSE_IN TIME_FROM_PTP_1588
  std::string operating_mode = "NORMAL";  // NORMAL STANDBY
  bool persist = false;                // save the configuration on the sensor (survives a power cycle)
  bool force_reinit = false;           // reinitialise even when nothing changes
  double timeout_s = 60;               // for reaching RUNNING (the SDK's default is 60 s)
  double http_timeout_s = 5;           // per request
  double poll_s = 0.5;                 // status polling period while waiting
  const std::atomic<bool>* cancel = nullptr;  // set -> the wait ends with SensorConfigError "cancelled"
};
// Throws SensorConfigError naming the parameter and the accepted values.
void validate(const SensorConfigRequest& req);

// The local IPv4 address the routing table picks to reach `host` (a connected UDP socket and
// getsockname: nothing is sent). Returns "" and sets *error when the host does not resolve or is
// unreachable.
std::string local_address_towards(const std::string& host, std::string* error);

// "host" or "host:port" as in Os1DriverOptions.sensor_hostname.
class SensorHttp {
 public:
  SensorHttp(std::string host, double timeout_s);
  // Throw SensorConfigError "http://HOST/path: ..." (no answer, HTTP status with the body's first line).
  std::string get(const std::string& path_and_query) const;
  std::string post_json(const std::string& path_and_query, const std::string& body) const;
  // As get, but returns false (with *status the HTTP status, 0 = no answer) instead of throwing.
  bool try_get(const std::string& path_and_query, std::string* body, int* status, std::string* error) const;
  const std::string& host() const { return host_; }
  std::string url(const std::string& path) const { return "http://" + host_ + path; }

 private:
  std::string host_, name_;
  int port_ = 80;
  double timeout_s_;
};

struct SensorSetupResult {
  FirmwareVersion firmware;
  std::string status;                // RUNNING or STANDBY
  std::string prod_line, serial;
  bool reinitialised = false;        // the configuration changed (or force_reinit) and the sensor restarted
  std::vector<std::string> changes;  // "lidar_mode 512x20 -> 1024x10"
  std::string udp_dest;              // as the sensor has it now
  std::string lidar_mode, udp_profile_lidar, timestamp_mode, operating_mode;
  std::string metadata_json;         // read after the change (nested layout; parse_metadata reads it)
  AlertReport alerts;
  double waited_s = 0;               // time spent waiting for RUNNING
  std::string summary() const;       // one line for logs and telemetry
};

using SetupProgress = std::function<void(const std::string&)>;
// The whole set-up. Throws SensorConfigError (host + parameter or state; for ERROR / UNCONFIGURED /
// timeouts the active alerts are part of the message).
SensorSetupResult configure_sensor(const std::string& host, const SensorConfigRequest& req,
                                   const SetupProgress& progress = {});

// Sensor status ("RUNNING", "INITIALIZING", ...) from sensor_info (fw 2.1: cmd/get_sensor_info).
std::string sensor_status(const SensorHttp& http, const FirmwareVersion& fw);
FirmwareVersion sensor_firmware(const SensorHttp& http);
AlertReport sensor_alerts(const SensorHttp& http, int64_t cursor = -1);

}  // namespace fploc::os1
