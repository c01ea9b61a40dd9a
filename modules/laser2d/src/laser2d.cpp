#include "fploc/laser2d/laser2d.h"

#include <Eigen/Geometry>
#include <cmath>

namespace fploc::laser2d {

feat::FeatureConfig Laser2dConfig::default_features() {
  feat::FeatureConfig c;
  c.sectors = 6;
  c.max_corners_per_sector = 4;
  c.max_surfaces_per_sector = 40;
  c.min_range_m = 0.05;
  c.max_range_m = 60.0;
  c.surface_spacing = 1;
  // 0.5-1 degree beams (SICK, Hokuyo) see a wall at 60-70 degrees incidence with range steps of a few per cent per
  // beam: LOAM's 2 % "parallel to the beam" rule (made for 0.1-0.35 degree spacing) would drop most walls.
  c.parallel_ratio = 0.15;
  // The smoothness c = |sum(X_j - X_i)| / |sum X_j| (LOAM's, with the neighbours' range: features/src/smoothness.h)
  // of a flat wall is not zero when the beams fall on it unevenly: it grows with the square of the beam spacing (about 0.005 at 45 degrees incidence for 1 degree
  // beams, 30x the OS-1's), while a real corner's grows only linearly (about 2 x spacing). Thresholds for
  // 0.25-1 degree scanners:
  c.corner_threshold = 0.03;
  c.surface_threshold = 0.008;
  return c;
}

Laser2dFeatures::Laser2dFeatures(Laser2dConfig cfg) : cfg_(cfg), fx_(cfg.features) {}

const FeatureFrame& Laser2dFeatures::process(const PlanarScan& s, double roll, double pitch, double rp_sigma) {
  stats_ = {};
  seg_.wall.clear();
  seg_.utime = s.utime;
  seg_.seq = s.seq;
  seg_.roll = roll;
  seg_.pitch = pitch;
  seg_.roll_pitch_sigma = rp_sigma;
  seg_.z = cfg_.z_m;
  seg_.z_sigma = 0.001;  // fixed
  seg_.attitude_t = 0;
  seg_.height = 1;
  seg_.width = int(s.ranges.size());
  stats_.beams = int(s.ranges.size());
  const bool geometry_ok = std::isfinite(s.angle_min) && std::isfinite(s.angle_increment) && s.angle_increment != 0 &&
                           std::isfinite(s.time_increment) && !s.ranges.empty() && s.ranges.size() < 32768;
  if (!geometry_ok) {
    seg_.status = seg::SegStatus::kBadInput;
    out_ = fx_.process(seg_);
    return out_;
  }
  const double lo = std::max<double>(cfg_.min_range_m, std::isfinite(s.range_min) ? s.range_min : 0.0);
  const double hi = std::min<double>(cfg_.max_range_m, std::isfinite(s.range_max) && s.range_max > 0 ? s.range_max : cfg_.max_range_m);
  const double cm = std::cos(cfg_.mount_yaw_rad), sm = std::sin(cfg_.mount_yaw_rad);
  for (size_t i = 0; i < s.ranges.size(); ++i) {
    const float r = s.ranges[i];
    if (!std::isfinite(r)) {
      ++stats_.dropped_non_finite;
      continue;
    }
    // hi is exclusive: CARMEN / SICK report "no return" as the maximum range.
    if (r < lo || r >= hi) {
      ++stats_.dropped_range;
      continue;
    }
    double a = double(s.angle_min) + double(i) * double(s.angle_increment);
    if (cfg_.upside_down) a = -a;
    const double lx = r * std::cos(a), ly = r * std::sin(a);
    const Eigen::Vector3f p(float(cfg_.mount_x_m + cm * lx - sm * ly), float(cfg_.mount_y_m + sm * lx + cm * ly), 0.f);
    seg_.wall.push(p, r, 0, int(i), float(double(i) * s.time_increment));
    ++stats_.returns;
  }
  seg_.status = seg_.wall.size() ? seg::SegStatus::kOk : seg::SegStatus::kEmpty;
  out_ = fx_.process(seg_);
  if (!cfg_.all_returns || out_.status == FeatureStatus::kBadInput) return out_;
  used_.assign(seg_.wall.size(), 0);
  for (int32_t k : fx_.source())
    if (k >= 0 && size_t(k) < used_.size()) used_[size_t(k)] = 1;
  const Eigen::Matrix3f R = (Eigen::AngleAxisf(float(pitch), Eigen::Vector3f::UnitY()) *
                             Eigen::AngleAxisf(float(roll), Eigen::Vector3f::UnitX())).toRotationMatrix();
  const auto& w = seg_.wall;
  for (size_t k = 0; k < w.size(); ++k) {
    if (used_[k]) continue;
    const Eigen::Vector3f p = R * Eigen::Vector3f(w.x[k], w.y[k], w.z[k]);
    Feature2 q;
    q.p = Eigen::Vector2d(p.x(), p.y());
    q.kind = FeatureKind::kSurface;
    q.group = -1;
    q.t = w.t[k];
    out_.points.push_back(q);
  }
  if (out_.size() >= 30 && out_.status == FeatureStatus::kFewFeatures) out_.status = FeatureStatus::kOk;
  return out_;
}

}  // namespace fploc::laser2d
