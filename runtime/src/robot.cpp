#include "fploc/runtime/robot.h"

#include <unistd.h>

#include <cstdlib>
#include <regex>

#include "fploc/runtime/bus.h"

namespace fploc::rt {

std::string robot_channel(const std::string& robot, const std::string& channel) {
  if (robot.empty() || channel.empty()) return channel;
  return robot + "/" + channel;
}

bool valid_robot_name(const std::string& robot) {
  static const std::regex re("[A-Za-z0-9_-]{0,32}");
  return std::regex_match(robot, re);
}

std::string robot_of(const fploc::Graph* g) {
  if (g && !g->robot().empty()) return g->robot();
  const char* e = std::getenv("FPLOC_ROBOT");
  return e ? e : "";
}

std::string graph_lcm_url(const fploc::Graph& g, const std::string& override_url) {
  std::string url = !override_url.empty() ? override_url : !g.lcm_url().empty() ? g.lcm_url() : kDefaultLcmUrl;
  if (g.lcm_ttl() <= 0 || url.rfind("udpm://", 0) != 0) return url;
  const std::regex ttl("([?&])ttl=[0-9]+");
  const std::string t = "ttl=" + std::to_string(g.lcm_ttl());
  if (std::regex_search(url, ttl)) return std::regex_replace(url, ttl, "$1" + t);
  return url + (url.find('?') == std::string::npos ? "?" : "&") + t;
}

std::string host_name() {
  char b[256] = {0};
  if (::gethostname(b, sizeof b - 1) != 0) return "";
  return b;
}

}  // namespace fploc::rt
