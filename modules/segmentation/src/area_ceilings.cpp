#include "fploc/segmentation/area_ceilings.h"

#include <algorithm>

namespace fploc::seg {

bool AreaCeiling::contains(const Eigen::Vector2d& p) const {
  // Even-odd rule (points on an edge may fall either way; areas share edges, the first one wins).
  bool in = false;
  const size_t n = polygon.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      in = !in;
  }
  return in;
}

void AreaCeilingMap::finish() {
  bbox.clear();
  for (const auto& a : areas) {
    Eigen::Vector4d b(1e300, 1e300, -1e300, -1e300);
    for (const auto& v : a.polygon) b = Eigen::Vector4d(std::min(b[0], v.x()), std::min(b[1], v.y()), std::max(b[2], v.x()), std::max(b[3], v.y()));
    bbox.push_back(b);
  }
}

int AreaCeilingMap::area_at(const Eigen::Vector2d& p) const {
  for (size_t i = 0; i < areas.size(); ++i) {
    if (i < bbox.size()) {
      const Eigen::Vector4d& b = bbox[i];
      if (p.x() < b[0] || p.y() < b[1] || p.x() > b[2] || p.y() > b[3]) continue;
    }
    if (areas[i].contains(p)) return int(i);
  }
  return -1;
}

const std::string& AreaCeilingMap::name(int area) const {
  static const std::string kDefault = "floor default";
  return area >= 0 && size_t(area) < areas.size() ? areas[size_t(area)].name : kDefault;
}

void AreaHeights::reset(const AreaCeilingMap& map, int window) {
  window_ = std::max(1, window);
  slots_.assign(map.areas.size() + 1, Slot{});
  slots_[0].given = map.default_height_m;
  for (size_t i = 0; i < map.areas.size(); ++i) {
    Slot& s = slots_[i + 1];
    s.given = map.areas[i].height_m;
    s.origin = map.areas[i].origin;
    s.slope = map.areas[i].slope;
  }
}

bool AreaHeights::known(int area) const { return area + 1 < int(slots_.size()) && slot(area).given > 0; }
bool AreaHeights::learned(int area) const { return area + 1 < int(slots_.size()) && slot(area).given <= 0 && !slot(area).seen.empty(); }
int AreaHeights::samples(int area) const { return area + 1 < int(slots_.size()) ? int(slot(area).seen.size()) : 0; }

double AreaHeights::height_at(int area, const Eigen::Vector2d& p) const {
  if (area + 1 >= int(slots_.size())) return 0;
  const Slot& s = slot(area);
  if (s.given > 0) return s.given + s.slope.dot(p - s.origin);
  return s.median;
}

void AreaHeights::learn(int area, double h) {
  if (area + 1 >= int(slots_.size()) || known(area)) return;
  Slot& s = slots_[size_t(area + 1)];
  s.seen.push_back(h);
  while (int(s.seen.size()) > window_) s.seen.pop_front();
  std::vector<double> v(s.seen.begin(), s.seen.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  s.median = v[v.size() / 2];
}

}  // namespace fploc::seg
