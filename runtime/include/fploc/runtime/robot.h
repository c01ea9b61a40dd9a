// Several robots on one network: a graph's `robot` namespaces every channel it uses ("r2/FPLOC_POSE"),
// so identical graphs of different robots never mix. One rule, used by nodes, the launcher, `fploc node`,
// `fploc replay`, `fploc spy` and the dashboard.
#pragma once
#include <string>

#include "graph.pb.h"

namespace fploc::rt {

// "<robot>/<channel>"; the channel itself when robot is "" or the channel is "" (not connected).
std::string robot_channel(const std::string& robot, const std::string& channel);
// Letters, digits, '_' and '-', at most 32 characters ("" is valid: no namespace).
bool valid_robot_name(const std::string& robot);
// The robot of a process: the graph's, else the environment's FPLOC_ROBOT, else "".
std::string robot_of(const fploc::Graph* g);
// The graph's LCM URL (or `override_url`) with Graph.lcm_ttl merged in as ttl= (replacing any ttl there).
std::string graph_lcm_url(const fploc::Graph& g, const std::string& override_url = "");
// This computer's host name (node_status_t.host).
std::string host_name();

}  // namespace fploc::rt
