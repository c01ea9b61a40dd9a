#include "laser_mounts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

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
  // The mean over the recording's time, not over tf's samples: each sample time of the path's edges weighs half the
  // time to its neighbours (the trapezoid rule over the interpolated transform), so a stretch where tf published
  // often, a value re-published many times or a static edge's extra stamps do not outweigh a long one sampled rarely.
  std::vector<int64_t> times;
  for (const int64_t t : p->times_ns)
    if (t >= p->start_ns) times.push_back(t);
  if (times.empty()) times.push_back(p->start_ns);  // every edge static
  double wsum = 0, sx = 0, sy = 0, sz = 0, sc = 0, ss = 0, snz = 0;
  m.tilt_min_deg = 180;
  m.tilt_max_deg = 0;
  for (size_t k = 0; k < times.size(); ++k) {
    const double w = times.size() == 1 ? 1.0
                                       : 0.5 * double((k + 1 < times.size() ? times[k + 1] : times[k]) -
                                                      (k > 0 ? times[k - 1] : times[k]));
    const Eigen::Isometry3d T = TfTree::at(*p, times[k]);
    const Eigen::Matrix3d R = T.linear();
    const double nz = R(2, 2);  // the scan plane's normal (the laser's z axis) on the base's z axis
    const double tilt = std::acos(std::min(1.0, std::abs(nz))) * 180 / M_PI;
    m.tilt_min_deg = std::min(m.tilt_min_deg, tilt);
    m.tilt_max_deg = std::max(m.tilt_max_deg, tilt);
    sx += w * T.translation().x(), sy += w * T.translation().y(), sz += w * T.translation().z();
    sc += w * R(0, 0), ss += w * R(1, 0), snz += w * nz;
    wsum += w;
  }
  m.x_m = sx / wsum, m.y_m = sy / wsum, m.z_m = sz / wsum;
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
