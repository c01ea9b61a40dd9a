// fploc os1 configure --sensor HOST [--udp-dest ADDR|@auto] [--lidar-mode 1024x10] [--profile P]
//   [--timestamp-mode M] [--operating-mode NORMAL|STANDBY] [--lidar-port 7502] [--imu-port 7503]
//   [--timeout S] [--persist] [--force-reinit] [--metadata-out F] [--alerts] [--json]
// Sets a live Ouster sensor up over its HTTP API as the OS-1 driver does on start (fploc/os1/sensor_config.h):
// prints the firmware, the changes, the final state and the active alerts; exit 0 when it reports RUNNING
// (or STANDBY when asked), 1 with one error line naming the host and the parameter otherwise.
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fploc/core/text_out.h"
#include "fploc/os1/sensor_config.h"
#include "fploc/runtime/cli_messages.h"

int main(int argc, char** argv) {
  CLI::App app{"fploc os1 configure: set a live Ouster sensor up over its HTTP API (firmware 2.1+)"};
  fploc::rt::install_cli_messages(app, "fploc os1 configure");
  std::string host, metadata_out;
  fploc::os1::SensorConfigRequest req;
  bool as_json = false, alerts_only = false;
  app.add_option("--sensor", host, "sensor host name or IP (host:port for a test server)")->required();
  app.add_option("--udp-dest", req.udp_dest, "where the sensor sends data: '' = this host's address towards it, @auto, or an IP");
  app.add_option("--lidar-mode", req.lidar_mode, "512x10 512x20 1024x10 1024x20 2048x10 4096x5 ('' = keep)");
  app.add_option("--profile", req.udp_profile_lidar, "udp_profile_lidar: LEGACY RNG19_RFL8_SIG16_NIR16 RNG15_RFL8_NIR8");
  app.add_option("--timestamp-mode", req.timestamp_mode, "TIME_FROM_INTERNAL_OSC TIME_FROM_SYNC_PULSE_IN TIME_FROM_PTP_1588");
  app.add_option("--operating-mode", req.operating_mode, "NORMAL or STANDBY");
  app.add_option("--lidar-port", req.udp_port_lidar, "udp_port_lidar (0 = keep)");
  app.add_option("--imu-port", req.udp_port_imu, "udp_port_imu (0 = keep)");
  app.add_option("--timeout", req.timeout_s, "seconds to wait for RUNNING");
  app.add_flag("--persist", req.persist, "save the configuration on the sensor");
  app.add_flag("--force-reinit", req.force_reinit, "reinitialise even when nothing changes");
  app.add_option("--metadata-out", metadata_out, "write the metadata read after the set-up here");
  app.add_flag("--alerts", alerts_only, "only print the sensor's status and alerts");
  app.add_flag("--json", as_json, "print the result as JSON");
  CLI11_PARSE(app, argc, argv);
  using nlohmann::json;
  try {
    if (alerts_only) {
      const fploc::os1::SensorHttp http(host, req.http_timeout_s);
      const auto fw = fploc::os1::sensor_firmware(http);
      const auto a = fploc::os1::sensor_alerts(http);
      std::cout << "firmware " << fw.str() << ", status " << fploc::os1::sensor_status(http, fw) << ", "
                << a.active.size() << " active alert(s)\n";
      for (const auto& x : a.active) std::cout << "  active " << x.text() << "\n";
      for (const auto& x : a.log) std::cout << "  log #" << x.cursor << (x.active ? " set   " : " clear ") << x.text() << "\n";
      return 0;
    }
    auto r = fploc::os1::configure_sensor(host, req, [&](const std::string& m) {
      if (!as_json) std::cerr << "fploc os1 configure: " << host << ": " << m << "\n";
    });
    if (!metadata_out.empty()) {
      std::ofstream f(metadata_out, std::ios::trunc);
      f << r.metadata_json;
      if (!f) throw fploc::os1::SensorConfigError("cannot write " + metadata_out);
    }
    if (as_json) {
      json alerts = json::array();
      for (const auto& x : r.alerts.active) alerts.push_back(x.text());
      std::cout << fploc::json_text(json{{"sensor", host}, {"firmware", r.firmware.str()}, {"status", r.status},
                                         {"reinitialised", r.reinitialised}, {"changes", r.changes}, {"udp_dest", r.udp_dest},
                                         {"lidar_mode", r.lidar_mode}, {"udp_profile_lidar", r.udp_profile_lidar},
                                         {"timestamp_mode", r.timestamp_mode}, {"operating_mode", r.operating_mode},
                                         {"waited_s", r.waited_s}, {"active_alerts", alerts}},
                                    2)
                << "\n";
    } else {
      std::cout << host << ": " << r.summary() << "\n";
      for (const auto& x : r.alerts.active) std::cout << "  active alert " << x.text() << "\n";
    }
    return 0;
  } catch (const fploc::os1::SensorConfigError& e) {
    std::cerr << "fploc os1 configure: " << e.what() << "\n";
    return 1;
  }
}
