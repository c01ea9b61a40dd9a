// The UDP links of a graph, for the stop order. A simulated sensor sends the drivers OS-1 packets over UDP,
// which is no LCM channel, so the supervisor's order (producers before consumers, by channel) would not see
// them: as the pseudo-channels "udp:PORT" the simulator stops before the drivers that listen on its ports, and
// the drivers still receive (and publish) what it sends while it stops. With both in the first rank, a
// simulator slow to stop under CPU load sent frames, and published their ground truth, after the drivers had
// exited: poses "missing" (demo_live).
#pragma once
#include <string>

#include "fploc/runtime/graph.h"
#include "supervisor.h"

namespace fploc::launch {

// Adds node n's UDP links to its policy: a sim_sensor's lidar and IMU ports as outputs; an os1_driver's lidar
// port (unless it reads a pcap or packets from LCM) and an imu_driver's IMU port (OS-1 source, no pcap) as
// inputs. `type` is the node's type (the executable's spec); other types have none.
void add_udp_links(const fploc::Node& n, const std::string& type, NodePolicy& p);

}  // namespace fploc::launch
