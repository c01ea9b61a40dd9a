#include "laser_mounts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fploc::import {

std::string robot_frame(const TfTree& tree, const std::string& preferred) {
  for (const std::string& f : {preferred, std::string("base_link"), std::string("base_footprint")})
    if (!f.empty() && tree.has(f)) return TfTree::bare(f);
  return "";
}

LaserMount laser_mount(const TfTree& tree, const std::string& base, const std::string& topic, const std::string& frame) {
  LaserMount m;
  m.topic = topic;
  m.frame = TfTree::bare(frame);
  m.base = base;
  if (m.frame.empty()) {
    m.why = "its scans name no frame (header.frame_id)";
    return m;
  }
  if (base.empty()) {
    m.why = "no robot frame in tf (base_link, base_footprint)";
    return m;
  }
  const auto p = tree.path(base, m.frame);
  if (!p) {
    m.why = tree.has(m.frame) ? "tf does not connect '" + base + "' and '" + m.frame + "'"
                              : "no tf frame '" + m.frame + "'";
    return m;
  }
  m.found = true;
  double n = 0, sx = 0, sy = 0, sz = 0, sc = 0, ss = 0, snz = 0;
  m.tilt_min_deg = 180;
  m.tilt_max_deg = 0;
  auto sample = [&](int64_t t) {
    const Eigen::Isometry3d T = TfTree::at(*p, t);
    const Eigen::Matrix3d R = T.linear();
    const double nz = R(2, 2);  // the scan plane's normal (the laser's z axis) on the base's z axis
    const double tilt = std::acos(std::min(1.0, std::abs(nz))) * 180 / M_PI;
    m.tilt_min_deg = std::min(m.tilt_min_deg, tilt);
    m.tilt_max_deg = std::max(m.tilt_max_deg, tilt);
    sx += T.translation().x(), sy += T.translation().y(), sz += T.translation().z();
    sc += R(0, 0), ss += R(1, 0), snz += nz;
    ++n;
  };
  bool any = false;
  for (const int64_t t : p->times_ns)
    if (t >= p->start_ns) sample(t), any = true;
  if (!any) sample(p->start_ns);  // every edge static
  m.x_m = sx / n, m.y_m = sy / n, m.z_m = sz / n;
  m.yaw_deg = std::atan2(ss, sc) * 180 / M_PI;
  m.upside_down = snz < 0;
  return m;
}

std::string LaserMount::describe() const {
  if (!found) return "mount unknown: " + why;
  char b[256];
  std::snprintf(b, sizeof b, "at x %.3f y %.3f z %.3f m, yaw %.1f deg%s on %s (tf)", x_m, y_m, z_m, yaw_deg,
                upside_down ? ", upside down" : "", base.c_str());
  std::string s = b;
  if (level()) return "level, " + s;
  std::snprintf(b, sizeof b, "tilted %.1f-%.1f deg from level", tilt_min_deg, tilt_max_deg);
  return std::string(b) + (tilt_max_deg - tilt_min_deg > 1 ? " (a tilting laser: not a planar scan for the 2D mode), "
                                                           : " (not a planar scan for the 2D mode), ") + s;
}

}  // namespace fploc::import
