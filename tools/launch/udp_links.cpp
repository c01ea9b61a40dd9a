#include "udp_links.h"

namespace fploc::launch {

void add_udp_links(const fploc::Node& n, const std::string& type, NodePolicy& p) {
  // Ports as the options document them: 0 = the Ouster defaults.
  auto udp = [](int port, int dflt) { return "udp:" + std::to_string(port > 0 ? port : dflt); };
  if (type == "sim_sensor") {
    p.outputs.push_back(udp(n.sim().lidar_port(), 7502));
    p.outputs.push_back(udp(n.sim().imu_port(), 7503));
  } else if (type == "os1_driver") {
    bool packets_from_lcm = false;
    for (const auto& in : n.input()) packets_from_lcm |= in.port() == "packets" && !in.channel().empty();
    if (n.os1_driver().pcap().empty() && !packets_from_lcm) p.inputs.push_back(udp(n.os1_driver().lidar_port(), 7502));
  } else if (type == "imu_driver") {
    const auto& o = n.imu_driver();
    if ((o.source().empty() || o.source() == "os1") && o.pcap().empty()) p.inputs.push_back(udp(o.imu_port(), 7503));
  }
}

}  // namespace fploc::launch
