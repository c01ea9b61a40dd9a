#include "fploc/laser2d/laser_odometry.h"

#include <algorithm>
#include <cmath>

#include "field_fit.h"
#include "fploc/floorplan/occupancy.h"
#include "fploc/floorplan/distance_field.h"

namespace fploc::laser2d {

struct LaserOdometry::Impl {
  struct Kept {
    Pose2 pose;                           // local frame
    std::vector<Eigen::Vector2d> world;   // its points in the local frame
  };
  std::deque<Kept> scans;
  Pose2 pose;          // the last scan's pose in the local frame
  bool have = false;

  // The local map's distance field: the kept scans' points rasterised around `centre`.
  std::shared_ptr<const DistanceField> field(const LaserOdometryConfig& c, const Pose2& centre) const {
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    const double half = 0.5 * c.max_map_extent_m;
    for (const auto& k : scans)
      for (const auto& p : k.world) {
        if (std::abs(p.x() - centre.x) > half || std::abs(p.y() - centre.y) > half) continue;
        x0 = std::min(x0, p.x());
        y0 = std::min(y0, p.y());
        x1 = std::max(x1, p.x());
        y1 = std::max(y1, p.y());
      }
    if (!(x1 >= x0)) return nullptr;
    const double m = c.field_max_m + c.resolution_m;
    OccupancyGrid g;
    g.resolution = c.resolution_m;
    g.origin_x = x0 - m;
    g.origin_y = y0 - m;
    g.width = int(std::ceil((x1 - x0 + 2 * m) / c.resolution_m)) + 1;
    g.height = int(std::ceil((y1 - y0 + 2 * m) / c.resolution_m)) + 1;
    g.occupied_thresh = 0.5;
    g.source = "laser odometry local map";
    g.data.assign(size_t(g.width) * size_t(g.height), 0);
    for (const auto& k : scans)
      for (const auto& p : k.world) {
        const int i = int(std::floor((p.x() - g.origin_x) / g.resolution));
        const int j = int(std::floor((p.y() - g.origin_y) / g.resolution));
        if (i < 0 || j < 0 || i >= g.width || j >= g.height) continue;
        g.data[size_t(j) * size_t(g.width) + size_t(i)] = 100;
      }
    return std::make_shared<const DistanceField>(g, c.field_max_m);
  }

  void keep(const LaserOdometryConfig& c, const Pose2& at, const std::vector<Eigen::Vector2d>& pts) {
    Kept k;
    k.pose = at;
    const double cs = std::cos(at.yaw), sn = std::sin(at.yaw);
    k.world.reserve(pts.size());
    for (const auto& p : pts) k.world.emplace_back(at.x + cs * p.x() - sn * p.y(), at.y + sn * p.x() + cs * p.y());
    scans.push_back(std::move(k));
    while (int(scans.size()) > std::max(1, c.map_scans)) scans.pop_front();
    pose = at;
    have = true;
  }
};

LaserOdometry::LaserOdometry(LaserOdometryConfig cfg) : impl_(std::make_unique<Impl>()), cfg_(cfg) {}
LaserOdometry::~LaserOdometry() = default;
LaserOdometry::LaserOdometry(LaserOdometry&&) noexcept = default;
LaserOdometry& LaserOdometry::operator=(LaserOdometry&&) noexcept = default;

void LaserOdometry::reset() { *impl_ = Impl{}; }

std::optional<LaserOdometryStep> LaserOdometry::update(const std::vector<Eigen::Vector2d>& pts, const Pose2& wheel_inc,
                                                       double sigma_xy_m, double sigma_yaw_rad) {
  Impl& m = *impl_;
  if (!m.have) {
    m.keep(cfg_, Pose2{}, pts);
    return std::nullopt;
  }
  const Pose2 pred = compose(m.pose, wheel_inc);
  std::optional<LaserOdometryStep> out;
  const auto df = pts.size() >= 10 ? m.field(cfg_, pred) : nullptr;
  if (df) {
    const detail::InterpolatedField f(df);
    detail::FieldFitOptions o;
    o.point_sigma_m = cfg_.point_sigma_m;
    o.huber_m = cfg_.huber_m;
    o.max_iterations = cfg_.max_iterations;
    const double sxy = std::max(sigma_xy_m, 1e-3), syaw = std::max(sigma_yaw_rad, 1e-4);
    double x[3] = {pred.x, pred.y, pred.yaw}, cost = 0;
    detail::refine_on_field(f, o, pts, pred, sxy, syaw, x, &cost, nullptr);
    const double ratio = double(detail::count_inliers(*df, pts, x, cfg_.inlier_m)) / double(pts.size());
    const double ex = x[0] - pred.x, ey = x[1] - pred.y, eyaw = wrap_angle(x[2] - pred.yaw);
    const double m2 = (ex * ex + ey * ey) / (sxy * sxy) + eyaw * eyaw / (syaw * syaw);
    if (ratio >= cfg_.min_inlier_ratio && m2 <= cfg_.gate_sigmas * cfg_.gate_sigmas) {
      const Pose2 at{x[0], x[1], wrap_angle(x[2])};
      out = LaserOdometryStep{between(m.pose, at), ratio};
      m.keep(cfg_, at, pts);
      return out;
    }
  }
  m.keep(cfg_, pred, pts);
  return out;
}

}  // namespace fploc::laser2d
