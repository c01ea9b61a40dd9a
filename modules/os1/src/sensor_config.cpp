#include "fploc/os1/sensor_config.h"

#include <arpa/inet.h>
#include <httplib.h>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>

namespace fploc::os1 {

using nlohmann::json;

namespace {

const std::vector<std::string> kLidarModes = {"512x10", "512x20", "1024x10", "1024x20", "2048x10", "4096x5"};
const std::vector<std::string> kDecodedProfiles = {"LEGACY", "RNG19_RFL8_SIG16_NIR16", "RNG15_RFL8_NIR8"};
const std::vector<std::string> kOtherProfiles = {"RNG19_RFL8_SIG16_NIR16_DUAL", "FUSA_RNG15_RFL8_NIR8_DUAL"};
const std::vector<std::string> kTimestampModes = {"TIME_FROM_INTERNAL_OSC", "TIME_FROM_SYNC_PULSE_IN",
                                                  "TIME_FROM_PTP_1588"};
const std::vector<std::string> kOperatingModes = {"NORMAL", "STANDBY"};

std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

bool one_of(const std::string& v, const std::vector<std::string>& set) {
  return std::find(set.begin(), set.end(), v) != set.end();
}

std::string first_line(std::string s, size_t max = 160) {
  if (const auto nl = s.find('\n'); nl != std::string::npos) s.resize(nl);
  if (s.size() > max) s = s.substr(0, max) + "...";
  return s;
}

json parse_json(const std::string& text, const std::string& source) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    throw SensorConfigError(source + ": not JSON (" + first_line(text, 60) + "): " + e.what());
  }
}

std::string as_text(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return "";
  return v.dump();
}

}  // namespace

std::string FirmwareVersion::str() const {
  return valid() ? "v" + std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch) : text;
}

FirmwareVersion parse_firmware_version(const std::string& s) {
  FirmwareVersion v;
  v.text = s;
  static const std::regex re(R"((?:^|[^0-9A-Za-z])v?(\d+)\.(\d+)\.(\d+))");
  std::smatch m;
  if (std::regex_search(s, m, re)) {
    v.major = std::stoi(m[1]);
    v.minor = std::stoi(m[2]);
    v.patch = std::stoi(m[3]);
  }
  return v;
}

std::string SensorAlert::text() const {
  std::string t = id + " " + level + " " + category + ": " + msg;
  if (!msg_verbose.empty()) t += " (" + msg_verbose + ")";
  return t;
}

AlertReport parse_alerts(const std::string& json_text, const std::string& source) {
  const json j = parse_json(json_text, source);
  if (!j.is_object()) throw SensorConfigError(source + ": expected a JSON object with 'active' and 'log'");
  AlertReport r;
  auto list = [&](const char* key, std::vector<SensorAlert>& out) {
    if (!j.contains(key)) return;
    if (!j[key].is_array()) throw SensorConfigError(source + ": '" + key + "' is not a list");
    for (const auto& a : j[key]) {
      if (!a.is_object()) throw SensorConfigError(source + ": '" + key + "' holds a non-object");
      SensorAlert s;
      s.id = as_text(a.value("id", json()));
      s.level = as_text(a.value("level", json()));
      s.category = as_text(a.value("category", json()));
      s.msg = as_text(a.value("msg", json()));
      s.msg_verbose = as_text(a.value("msg_verbose", json()));
      s.active = a.value("active", json(false)).is_boolean() ? a["active"].get<bool>() : false;
      if (a.contains("cursor") && a["cursor"].is_number_integer()) s.cursor = a["cursor"].get<int64_t>();
      out.push_back(std::move(s));
    }
  };
  list("active", r.active);
  list("log", r.log);
  if (j.contains("next_cursor") && j["next_cursor"].is_number_integer()) r.next_cursor = j["next_cursor"].get<int64_t>();
  return r;
}

void validate(const SensorConfigRequest& r) {
  if (!r.lidar_mode.empty() && !one_of(r.lidar_mode, kLidarModes))
    throw SensorConfigError("lidar_mode '" + r.lidar_mode + "' is not an Ouster lidar mode (" + join(kLidarModes) + ")");
  if (!r.udp_profile_lidar.empty() && !one_of(r.udp_profile_lidar, kDecodedProfiles)) {
    if (one_of(r.udp_profile_lidar, kOtherProfiles))
      throw SensorConfigError("udp_profile_lidar '" + r.udp_profile_lidar + "' is not decoded by fploc (use " +
                              join(kDecodedProfiles) + ")");
    throw SensorConfigError("udp_profile_lidar '" + r.udp_profile_lidar + "' is not an Ouster lidar profile (" +
                            join(kDecodedProfiles) + ")");
  }
  if (!r.timestamp_mode.empty() && !one_of(r.timestamp_mode, kTimestampModes))
    throw SensorConfigError("timestamp_mode '" + r.timestamp_mode + "' is not one of " + join(kTimestampModes));
  if (!r.operating_mode.empty() && !one_of(r.operating_mode, kOperatingModes))
    throw SensorConfigError("operating_mode '" + r.operating_mode + "' is not one of " + join(kOperatingModes));
  if (r.udp_port_lidar < 0 || r.udp_port_lidar > 65535)
    throw SensorConfigError("udp_port_lidar " + std::to_string(r.udp_port_lidar) + " is not a port");
  if (r.udp_port_imu < 0 || r.udp_port_imu > 65535)
    throw SensorConfigError("udp_port_imu " + std::to_string(r.udp_port_imu) + " is not a port");
  if (!(r.timeout_s > 0)) throw SensorConfigError("sensor_timeout_s must be > 0");
  if (r.udp_dest.find_first_of(" \t\"") != std::string::npos)
    throw SensorConfigError("udp_dest '" + r.udp_dest + "' is not an address");
}

std::string local_address_towards(const std::string& host_port, std::string* error) {
  std::string host = host_port;
  if (const auto c = host.rfind(':'); c != std::string::npos && host.find(':') == c) host.resize(c);
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  if (const int rc = getaddrinfo(host.c_str(), "80", &hints, &res); rc != 0 || !res) {
    *error = "sensor '" + host + "' does not resolve to an IPv4 address (" + gai_strerror(rc) + ")";
    return "";
  }
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  std::string out;
  if (fd < 0) {
    *error = std::string("socket: ") + std::strerror(errno);
  } else if (::connect(fd, res->ai_addr, res->ai_addrlen) != 0) {  // UDP: a route lookup, no packet
    *error = "no route to the sensor '" + host + "' (" + std::strerror(errno) + ")";
  } else {
    sockaddr_in local{};
    socklen_t len = sizeof local;
    char buf[INET_ADDRSTRLEN] = {};
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len) == 0 &&
        inet_ntop(AF_INET, &local.sin_addr, buf, sizeof buf))
      out = buf;
    else
      *error = std::string("getsockname: ") + std::strerror(errno);
  }
  if (fd >= 0) ::close(fd);
  freeaddrinfo(res);
  return out;
}

// ---- HTTP ------------------------------------------------------------------------------------------

SensorHttp::SensorHttp(std::string host, double timeout_s) : host_(std::move(host)), name_(host_), timeout_s_(timeout_s) {
  if (const auto colon = host_.rfind(':'); colon != std::string::npos && host_.find(':') == colon) {
    name_ = host_.substr(0, colon);
    try {
      port_ = std::stoi(host_.substr(colon + 1));
    } catch (const std::exception&) {
      port_ = -1;
    }
    if (port_ <= 0 || port_ > 65535) throw SensorConfigError("sensor_hostname '" + host_ + "': bad port");
  }
}

namespace {
// Error messages name the endpoint; a long query (a whole configuration) is shortened.
std::string short_path(const std::string& path) {
  const auto q = path.find('?');
  return q != std::string::npos && path.size() > q + 40 ? path.substr(0, q) + "?..." : path;
}
}  // namespace

bool SensorHttp::try_get(const std::string& path, std::string* body, int* status, std::string* error) const {
  httplib::Client cli(name_, port_);
  const auto sec = time_t(timeout_s_), usec = time_t(std::fmod(timeout_s_, 1.0) * 1e6);
  cli.set_connection_timeout(sec, usec);
  cli.set_read_timeout(sec, usec);
  cli.set_url_encode(false);  // our queries are encoded already; '+' separates a command's arguments
  auto res = cli.Get(path.c_str());
  if (!res) {
    *status = 0;
    *error = url(short_path(path)) + ": no answer (" + httplib::to_string(res.error()) + " error)";
    return false;
  }
  *status = res->status;
  *body = res->body;
  if (res->status != 200) {
    *error = url(short_path(path)) + ": HTTP " + std::to_string(res->status) + (res->body.empty() ? "" : " " + first_line(res->body));
    return false;
  }
  return true;
}

std::string SensorHttp::get(const std::string& path) const {
  std::string body, err;
  int status = 0;
  if (!try_get(path, &body, &status, &err)) throw SensorConfigError(err);
  return body;
}

std::string SensorHttp::post_json(const std::string& path, const std::string& body) const {
  httplib::Client cli(name_, port_);
  const auto sec = time_t(timeout_s_), usec = time_t(std::fmod(timeout_s_, 1.0) * 1e6);
  cli.set_connection_timeout(sec, usec);
  cli.set_read_timeout(sec, usec);
  cli.set_url_encode(false);
  auto res = cli.Post(path.c_str(), body, "application/json");
  if (!res) throw SensorConfigError(url(path) + ": no answer (" + httplib::to_string(res.error()) + " error)");
  if (res->status < 200 || res->status >= 300)
    throw SensorConfigError(url(path) + ": HTTP " + std::to_string(res->status) +
                            (res->body.empty() ? "" : " " + first_line(res->body)));
  return res->body;
}

FirmwareVersion sensor_firmware(const SensorHttp& http) {
  std::string body, err;
  int status = 0;
  const std::string path = "/api/v1/system/firmware";
  if (!http.try_get(path, &body, &status, &err)) {
    if (status == 404)
      throw SensorConfigError(http.url(path) + ": HTTP 404: this sensor has no HTTP API (firmware older than 2.1, "
                              "TCP API on port 7501 only); fploc configures firmware 2.1 or later: upgrade the sensor "
                              "or set keep_sensor_config and use a metadata file");
    throw SensorConfigError(err);
  }
  const json j = parse_json(body, http.url(path));
  if (!j.is_object() || !j.contains("fw") || !j["fw"].is_string())
    throw SensorConfigError(http.url(path) + ": no 'fw' string in " + first_line(body, 80));
  FirmwareVersion fw = parse_firmware_version(j["fw"].get<std::string>());
  if (!fw.valid())
    throw SensorConfigError(http.url(path) + ": firmware '" + fw.text + "' has no version number vX.Y.Z");
  if (!fw.at_least(2, 1))
    throw SensorConfigError("sensor " + http.host() + ": firmware " + fw.str() + " ('" + fw.text +
                            "') is not supported: fploc configures firmware 2.1 or later over HTTP (2.0 and 1.x "
                            "have the TCP API on port 7501 only); upgrade the sensor, or set keep_sensor_config "
                            "and configure it elsewhere");
  return fw;
}

std::string sensor_status(const SensorHttp& http, const FirmwareVersion& fw) {
  const std::string path = fw.at_least(2, 2) ? "/api/v1/sensor/metadata/sensor_info" : "/api/v1/sensor/cmd/get_sensor_info";
  const json j = parse_json(http.get(path), http.url(path));
  if (!j.is_object() || !j.contains("status") || !j["status"].is_string())
    throw SensorConfigError(http.url(path) + ": no 'status' string");
  return j["status"].get<std::string>();
}

AlertReport sensor_alerts(const SensorHttp& http, int64_t cursor) {
  const std::string path = "/api/v1/sensor/alerts" + (cursor >= 0 ? "?cursor=" + std::to_string(cursor) : std::string());
  return parse_alerts(http.get(path), http.url(path));
}

namespace {

// The configuration API of the firmware generation.
struct ConfigApi {
  const SensorHttp& http;
  const FirmwareVersion& fw;
  bool modern() const { return fw.major >= 3; }

  json read(bool active) const {
    const std::string path = modern() && active ? "/api/v1/sensor/config"
                                                : std::string("/api/v1/sensor/cmd/get_config_param?args=") +
                                                      (active ? "active" : "staged");
    json j = parse_json(http.get(path), http.url(path));
    if (!j.is_object()) throw SensorConfigError(http.url(path) + ": the configuration is not a JSON object");
    return j;
  }

  // fw 2.x: one set_config_param with the whole merged configuration (as the SDK does), then reinitialize.
  // fw 3+: POST only the changed keys to /api/v1/sensor/config, which reinitialises.
  void write(const json& merged, const json& changed, bool persist, bool reinit) const {
    std::string keys;
    for (const auto& [k, v] : changed.items()) keys += (keys.empty() ? "" : ", ") + k + "=" + as_text(v);
    try {
      if (modern()) {
        http.post_json(std::string("/api/v1/sensor/config?reinit=") + (reinit ? "true" : "false") +
                           "&persist=" + (persist ? "true" : "false"),
                       changed.dump());
        return;
      }
      const std::string set = "/api/v1/sensor/cmd/set_config_param?args=.+" + httplib::detail::encode_query_param(merged.dump());
      const std::string r = http.get(set);
      if (r != "\"set_config_param\"")
        throw SensorConfigError(http.url("/api/v1/sensor/cmd/set_config_param") + ": answered '" + first_line(r, 80) +
                                "', expected \"set_config_param\"");
      if (reinit) expect_ok("/api/v1/sensor/cmd/reinitialize");
      if (persist) expect_ok("/api/v1/sensor/cmd/save_config_params");
    } catch (const SensorConfigError& e) {
      throw SensorConfigError(std::string(e.what()) + " (setting " + keys + ")");
    }
  }

  void expect_ok(const std::string& path) const {
    const std::string r = http.get(path);
    if (r != "{}" && r != "\"set_config_param\"")
      throw SensorConfigError(http.url(path) + ": answered '" + first_line(r, 80) + "', expected {}");
  }

  // The UDP destination the sensor detects (the address its HTTP request came from).
  void udp_dest_auto(json& params) const {
    if (modern()) {
      params["udp_dest"] = "@auto";
      return;
    }
    expect_ok("/api/v1/sensor/cmd/set_udp_dest_auto");
    const json staged = read(false);
    for (const char* k : {"udp_ip", "udp_dest"})
      if (staged.contains(k) && params.contains(k)) params[k] = staged[k];
    if (staged.contains("udp_ip") && !params.contains("udp_ip")) params["udp_dest"] = staged["udp_ip"];
  }

  std::string metadata() const {
    if (fw.at_least(2, 2)) return http.get("/api/v1/sensor/metadata");
    json root;  // fw 2.1: the SDK assembles the nested layout from the cmd endpoints
    const std::pair<const char*, const char*> parts[] = {{"sensor_info", "get_sensor_info"},
                                                         {"beam_intrinsics", "get_beam_intrinsics"},
                                                         {"imu_intrinsics", "get_imu_intrinsics"},
                                                         {"lidar_intrinsics", "get_lidar_intrinsics"},
                                                         {"lidar_data_format", "get_lidar_data_format"}};
    for (const auto& [key, cmd] : parts) {
      const std::string path = std::string("/api/v1/sensor/cmd/") + cmd;
      root[key] = parse_json(http.get(path), http.url(path));
    }
    root["config_params"] = read(true);
    return root.dump();
  }
};

std::string active_alert_text(const SensorHttp& http) {
  try {
    const AlertReport a = sensor_alerts(http);
    if (a.active.empty()) return "no active alerts";
    std::vector<std::string> t;
    for (const auto& x : a.active) t.push_back(x.text());
    return std::to_string(a.active.size()) + " active alert" + (a.active.size() > 1 ? "s" : "") + ": " + join(t, "; ");
  } catch (const SensorConfigError& e) {
    return std::string("alerts unavailable: ") + e.what();
  }
}

}  // namespace

std::string SensorSetupResult::summary() const {
  std::string s = prod_line.empty() ? "sensor" : prod_line;
  if (!serial.empty()) s += " sn " + serial;
  s += " fw " + firmware.str() + ": " + status + ", " + lidar_mode + " " + udp_profile_lidar + " " + timestamp_mode +
       ", udp_dest " + udp_dest;
  char waited[32];
  std::snprintf(waited, sizeof waited, "%.1f", waited_s);
  s += reinitialised ? " (reconfigured: " + join(changes) + "; " + status + " after " + waited + " s)"
                     : " (configuration unchanged)";
  if (!alerts.active.empty()) s += "; " + std::to_string(alerts.active.size()) + " active alert(s)";
  return s;
}

SensorSetupResult configure_sensor(const std::string& host, const SensorConfigRequest& req, const SetupProgress& progress) {
  validate(req);
  auto say = [&](const std::string& m) {
    if (progress) progress(m);
  };
  const SensorHttp http(host, req.http_timeout_s);
  SensorSetupResult out;
  out.firmware = sensor_firmware(http);
  const ConfigApi api{http, out.firmware};
  say("firmware " + out.firmware.str());

  // Desired parameters.
  json want = json::object();
  std::string udp_dest = req.udp_dest;
  if (udp_dest.empty()) {
    std::string err;
    udp_dest = local_address_towards(host, &err);
    if (udp_dest.empty()) throw SensorConfigError("udp_dest: cannot find this host's address towards " + host + ": " + err);
    say("udp_dest " + udp_dest + " (this host's address on the route to " + host + ")");
  }
  if (udp_dest != "@auto") want["udp_dest"] = udp_dest;
  if (req.udp_port_lidar > 0) want["udp_port_lidar"] = req.udp_port_lidar;
  if (req.udp_port_imu > 0) want["udp_port_imu"] = req.udp_port_imu;
  if (!req.lidar_mode.empty()) want["lidar_mode"] = req.lidar_mode;
  if (!req.udp_profile_lidar.empty()) want["udp_profile_lidar"] = req.udp_profile_lidar;
  if (!req.timestamp_mode.empty()) want["timestamp_mode"] = req.timestamp_mode;
  if (!req.operating_mode.empty()) want["operating_mode"] = req.operating_mode;

  const json active = api.read(true);
  json merged = active;
  for (const auto& [k, v] : want.items()) {
    if (k == "udp_profile_lidar" && !active.contains(k)) {
      if (v != "LEGACY")
        throw SensorConfigError("sensor " + host + ": udp_profile_lidar " + as_text(v) + ": firmware " +
                                out.firmware.str() + " has no packet profiles (LEGACY only; 2.2 or later needed)");
      continue;
    }
    if (k == "udp_dest" && active.contains("udp_ip") && !active.contains("udp_dest")) merged["udp_ip"] = v;
    else merged[k] = v;
  }
  if (want.contains("operating_mode") && active.contains("auto_start_flag"))
    merged["auto_start_flag"] = want["operating_mode"] == "NORMAL" ? 1 : 0;
  if (udp_dest == "@auto") api.udp_dest_auto(merged);

  json changed = json::object();
  for (const auto& [k, v] : merged.items())
    if (!active.contains(k) || active[k] != v) {
      changed[k] = v;
      out.changes.push_back(k + " " + (active.contains(k) ? as_text(active[k]) : "(none)") + " -> " + as_text(v));
    }
  if (udp_dest == "@auto" && api.modern()) {  // @auto is resolved by the sensor itself
    changed["udp_dest"] = "@auto";
    if (std::find_if(out.changes.begin(), out.changes.end(), [](const std::string& c) { return c.rfind("udp_dest", 0) == 0; }) ==
        out.changes.end())
      out.changes.push_back("udp_dest -> @auto");
  }

  const bool target_standby = req.operating_mode == "STANDBY";
  const auto t0 = std::chrono::steady_clock::now();
  if (!changed.empty() || req.force_reinit) {
    say("setting " + join(out.changes));
    api.write(merged, changed, req.persist, true);
    out.reinitialised = true;
  } else {
    say("configuration already as asked");
  }

  // Wait for RUNNING (or STANDBY). The HTTP server may not answer for a moment while reinitialising.
  std::string status, last_err;
  const auto deadline = t0 + std::chrono::duration<double>(req.timeout_s);
  for (;;) {
    try {
      status = sensor_status(http, out.firmware);
      last_err.clear();
    } catch (const SensorConfigError& e) {
      last_err = e.what();
      status = "(no answer)";
    }
    if (req.cancel && req.cancel->load()) throw SensorConfigError("sensor " + host + ": set-up cancelled (shutdown)");
    if (status == "RUNNING" && !target_standby) break;
    if (status == "STANDBY" && target_standby) break;
    if (status == "ERROR" || status == "UNCONFIGURED")
      throw SensorConfigError("sensor " + host + " reports status " + status + " after configuration; " +
                              active_alert_text(http));
    if (status == "STANDBY" && !target_standby)
      throw SensorConfigError("sensor " + host + " stays in STANDBY although operating_mode NORMAL was set");
    if (std::chrono::steady_clock::now() >= deadline) {
      std::ostringstream m;
      m << "sensor " << host << ": timeout after " << req.timeout_s << " s (sensor_timeout_s) waiting for "
        << (target_standby ? "STANDBY" : "RUNNING") << "; last status " << status;
      if (!last_err.empty()) m << " (" << last_err << ")";
      m << "; " << active_alert_text(http);
      throw SensorConfigError(m.str());
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(req.poll_s));
  }
  out.waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.status = status;
  say("status " + status);

  // What the sensor has now: the configuration must be what was asked (a sensor may refuse silently).
  const json now = api.read(true);
  for (const auto& [k, v] : want.items()) {
    if (k == "udp_profile_lidar" && !now.contains(k)) continue;
    const char* key = (k == "udp_dest" && now.contains("udp_ip") && !now.contains("udp_dest")) ? "udp_ip" : k.c_str();
    if (now.contains(key) && now[key] != v)
      throw SensorConfigError("sensor " + host + ": " + k + " is " + as_text(now[key]) + " after setting " + as_text(v));
  }
  auto get = [&](const char* k) { return now.contains(k) ? as_text(now[k]) : std::string(); };
  out.udp_dest = get("udp_dest").empty() ? get("udp_ip") : get("udp_dest");
  out.lidar_mode = get("lidar_mode");
  out.udp_profile_lidar = get("udp_profile_lidar").empty() ? "LEGACY" : get("udp_profile_lidar");
  out.timestamp_mode = get("timestamp_mode");
  out.operating_mode = get("operating_mode");

  if (!target_standby) {
    out.metadata_json = api.metadata();  // re-read after the change
    const json meta = parse_json(out.metadata_json, http.url("/api/v1/sensor/metadata"));
    if (meta.contains("sensor_info") && meta["sensor_info"].is_object()) {
      out.prod_line = as_text(meta["sensor_info"].value("prod_line", json()));
      out.serial = as_text(meta["sensor_info"].value("prod_sn", json()));
    }
  }
  try {
    out.alerts = sensor_alerts(http);
  } catch (const SensorConfigError& e) {
    say(std::string("alerts unavailable: ") + e.what());
  }
  return out;
}

}  // namespace fploc::os1
