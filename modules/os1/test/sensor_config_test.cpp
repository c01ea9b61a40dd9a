// The parts of the live sensor set-up that need no sensor: firmware strings, the alerts JSON of the
// Ouster HTTP API, parameter validation, the route lookup. The HTTP protocol itself is tested against a
// fake sensor in a network namespace (tests/os1/sensor_config_test.sh).
#include <gtest/gtest.h>

#include "fploc/os1/sensor_config.h"

using namespace fploc::os1;

TEST(SensorConfig, FirmwareVersions) {
  auto v = parse_firmware_version("ousteros-image-prod-aries-v2.3.0+20220415163956");
  EXPECT_EQ(v.major, 2);
  EXPECT_EQ(v.minor, 3);
  EXPECT_EQ(v.patch, 0);
  EXPECT_EQ(v.str(), "v2.3.0");
  EXPECT_TRUE(v.at_least(2, 1));
  EXPECT_FALSE(v.at_least(3, 0));
  v = parse_firmware_version("ousteros-image-prod-bootes-v3.1.0-rc.2+0123456789");
  EXPECT_EQ(v.major, 3);
  EXPECT_EQ(v.minor, 1);
  EXPECT_EQ(parse_firmware_version("v2.5.0-omega.8").str(), "v2.5.0");
  EXPECT_EQ(parse_firmware_version("2.1.2").str(), "v2.1.2");
  EXPECT_FALSE(parse_firmware_version("ousteros-image-prod-aries").valid());
  EXPECT_FALSE(parse_firmware_version("").valid());
}

TEST(SensorConfig, AlertsJson) {
  // The shape of GET /api/v1/sensor/alerts (Ouster manual, get_alerts).
  const std::string j = R"({"next_cursor": 2,
    "active": [{"category": "UDP_TRANSMISSION", "msg": "Received an unknown error when trying to send lidar data UDP packet; closing socket.",
                "realtime": "1569631015375767040", "cursor": 0, "id": "0x01000017", "active": true,
                "msg_verbose": "192.0.2.123:7502", "level": "WARNING"}],
    "log": [{"category": "UDP_TRANSMISSION", "msg": "a", "realtime": "1569631015375767040", "cursor": 0,
             "id": "0x01000017", "active": true, "msg_verbose": "192.0.2.123:7502", "level": "WARNING"},
            {"category": "UDP_TRANSMISSION", "msg": "b", "realtime": "1569631015883802368", "cursor": 1,
             "id": "0x0100001a", "active": false, "msg_verbose": "192.0.2.123:7503", "level": "WARNING"}]})";
  const AlertReport r = parse_alerts(j, "test");
  ASSERT_EQ(r.active.size(), 1u);
  ASSERT_EQ(r.log.size(), 2u);
  EXPECT_EQ(r.next_cursor, 2);
  EXPECT_EQ(r.active[0].id, "0x01000017");
  EXPECT_EQ(r.active[0].level, "WARNING");
  EXPECT_TRUE(r.active[0].active);
  EXPECT_FALSE(r.log[1].active);
  EXPECT_EQ(r.log[1].cursor, 1);
  EXPECT_NE(r.active[0].text().find("0x01000017 WARNING UDP_TRANSMISSION: Received"), std::string::npos);
  EXPECT_NE(r.active[0].text().find("(192.0.2.123:7502)"), std::string::npos);
  EXPECT_EQ(parse_alerts("{}", "t").active.size(), 0u);
  try {
    parse_alerts("<html>", "http://h/api/v1/sensor/alerts");
    FAIL();
  } catch (const SensorConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("http://h/api/v1/sensor/alerts: not JSON"), std::string::npos);
  }
  EXPECT_THROW(parse_alerts(R"({"active": 3})", "t"), SensorConfigError);
}

TEST(SensorConfig, ValidateNamesTheParameter) {
  SensorConfigRequest ok;
  ok.lidar_mode = "2048x10";
  ok.udp_profile_lidar = "RNG15_RFL8_NIR8";
  ok.timestamp_mode = "TIME_FROM_PTP_1588";
  EXPECT_NO_THROW(validate(ok));
  auto message = [](SensorConfigRequest r) {
    try {
      validate(r);
    } catch (const SensorConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  SensorConfigRequest r = ok;
  r.lidar_mode = "1024x15";
  EXPECT_EQ(message(r).rfind("lidar_mode '1024x15'", 0), 0u);
  r = ok;
  r.timestamp_mode = "PTP";
  EXPECT_EQ(message(r).rfind("timestamp_mode 'PTP'", 0), 0u);
  r = ok;
  r.operating_mode = "ON";
  EXPECT_EQ(message(r).rfind("operating_mode 'ON'", 0), 0u);
  r = ok;
  r.udp_profile_lidar = "FUSA_RNG15_RFL8_NIR8_DUAL";
  EXPECT_NE(message(r).find("not decoded by fploc"), std::string::npos);
  r = ok;
  r.udp_port_lidar = 70000;
  EXPECT_EQ(message(r).rfind("udp_port_lidar 70000", 0), 0u);
  r = ok;
  r.timeout_s = 0;
  EXPECT_NE(message(r).find("sensor_timeout_s"), std::string::npos);
}

TEST(SensorConfig, LocalAddressFromTheRoutingTable) {
  std::string err;
  EXPECT_EQ(local_address_towards("127.0.0.1:8080", &err), "127.0.0.1") << err;  // a route lookup, nothing sent
}
