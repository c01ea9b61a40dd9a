#include "udp_links.h"

#include "fploc/os1/ports.h"

namespace fploc::launch {

void add_udp_links(const fploc::Node& n, const std::string& type, NodePolicy& p) {
  auto udp = [](int port, int dflt) { return "udp:" + std::to_string(os1::port_or_default(port, dflt)); };
  if (type == "sim_sensor") {
    p.outputs.push_back(udp(n.sim().lidar_port(), os1::kDefaultLidarPort));
    p.outputs.push_back(udp(n.sim().imu_port(), os1::kDefaultImuPort));
  } else if (type == "os1_driver") {
    bool packets_from_lcm = false;
    for (const auto& in : n.input()) packets_from_lcm |= in.port() == "packets" && !in.channel().empty();
    if (n.os1_driver().pcap().empty() && !packets_from_lcm) p.inputs.push_back(udp(n.os1_driver().lidar_port(), os1::kDefaultLidarPort));
  } else if (type == "imu_driver") {
    const auto& o = n.imu_driver();
    if ((o.source().empty() || o.source() == "os1") && o.pcap().empty()) p.inputs.push_back(udp(o.imu_port(), os1::kDefaultImuPort));
  }
}

}  // namespace fploc::launch
