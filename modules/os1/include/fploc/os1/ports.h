// The UDP ports an Ouster sensor sends to by default (its udp_port_lidar / udp_port_imu); 0 in fploc's
// options means these. One place, so the nodes that send or listen and the launcher's stop order (which links
// a simulated sensor to the drivers on its ports) agree.
#pragma once

namespace fploc::os1 {

inline constexpr int kDefaultLidarPort = 7502;
inline constexpr int kDefaultImuPort = 7503;

// `port` as an option gives it (> 0), else the default.
inline int port_or_default(int port, int dflt) { return port > 0 ? port : dflt; }

}  // namespace fploc::os1
