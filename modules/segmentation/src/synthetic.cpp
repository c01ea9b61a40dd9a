#include "fploc/segmentation/synthetic.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "fploc/core/xyz.h"

namespace fploc::seg::synth {

BeamIntrinsics os1_like_beams(int n) {
  BeamIntrinsics b;
  const double az[4] = {3.164, 1.055, -1.055, -3.164};
  for (int u = 0; u < n; ++u) {
    b.altitude_deg.push_back(16.6 - 33.2 * u / std::max(1, n - 1));
    b.azimuth_deg.push_back(az[u % 4]);
    b.pixel_shift_by_row.push_back(18 - 6 * (u % 4));
  }
  b.beam_offset_mm = 27.67;
  return b;
}

Room furnished_room() {
  Room r;
  r.boxes.push_back({{2.0, 2.0, 0.0}, {2.5, 2.5, 3.0}, kWall});        // square pillar
  r.boxes.push_back({{-4.3, -2.3, 0.0}, {-3.7, -1.7, 3.0}, kWall});    // pillar
  r.boxes.push_back({{-2.0, 3.0, 0.0}, {0.0, 4.0, 0.75}, kClutter});   // table
  r.boxes.push_back({{5.0, -5.5, 0.0}, {7.5, -5.0, 2.0}, kClutter});   // cabinet at a wall
  r.boxes.push_back({{3.0, -1.0, 0.0}, {3.4, -0.6, 1.8}, kClutter});   // person
  r.boxes.push_back({{-7.0, 4.0, 0.0}, {-5.5, 5.5, 1.1}, kClutter});   // desk
  return r;
}

double Room::floor_at(double x) const {
  if (ramp.x1 <= ramp.x0 || x <= ramp.x0) return 0.0;
  if (x >= ramp.x1) return ramp.rise;
  return ramp.rise * (x - ramp.x0) / (ramp.x1 - ramp.x0);
}

namespace {
// Distance along a ray to the floor with a ramp (hit from above only): the lower floor before x0, the
// slope, the landing after x1; +inf if missed.
double hit_ramp_floor(const Room::Ramp& r, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  if (d.z() < 0) {
    const double t0 = -o.z() / d.z();
    if (t0 > 1e-6 && o.x() + t0 * d.x() <= r.x0) best = std::min(best, t0);
    const double t2 = (r.rise - o.z()) / d.z();
    if (t2 > 1e-6 && o.x() + t2 * d.x() >= r.x1) best = std::min(best, t2);
  }
  const double s = r.rise / (r.x1 - r.x0), den = d.z() - s * d.x();
  if (den < 0) {
    const double t1 = (s * (o.x() - r.x0) - o.z()) / den;
    const double x = o.x() + t1 * d.x();
    if (t1 > 1e-6 && x >= r.x0 && x <= r.x1) best = std::min(best, t1);
  }
  return best;
}

// The same for a ceiling `h` above that floor, hit from below.
double hit_ramp_ceiling(const Room::Ramp& r, double h, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  if (d.z() > 0) {
    const double t0 = (h - o.z()) / d.z();
    if (t0 > 1e-6 && o.x() + t0 * d.x() <= r.x0) best = std::min(best, t0);
  }
  const double ls = r.landing_ceiling_slope, den2 = d.z() - ls * d.x();  // the landing's ceiling, maybe sloped
  if (den2 > 0) {
    const double t2 = (h + r.rise + ls * (o.x() - r.x1) - o.z()) / den2;
    if (t2 > 1e-6 && o.x() + t2 * d.x() >= r.x1) best = std::min(best, t2);
  }
  const double s = r.rise / (r.x1 - r.x0), den = d.z() - s * d.x();
  if (den > 0) {
    const double t1 = (h + s * (o.x() - r.x0) - o.z()) / den;
    const double x = o.x() + t1 * d.x();
    if (t1 > 1e-6 && x >= r.x0 && x <= r.x1) best = std::min(best, t1);
  }
  return best;
}

// Entry distance of a ray into an axis-aligned box (slab test); +inf if missed.
double hit_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < b.lo[k] || o[k] > b.hi[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0 > 1e-6 ? t0 : std::numeric_limits<double>::infinity();
}
}  // namespace

SynthScan render(const Room& room, const SensorPose& pose, const BeamIntrinsics& beams, int width,
                 double noise, double dropout, uint32_t seed) {
  SynthScan out;
  Scan& s = out.scan;
  s.beams = beams;
  s.resize(beams.beams(), width);
  s.sensor = "synthetic";
  out.label.assign(s.range_mm.size(), kNone);
  const XyzLut lut = make_xyz_lut(beams, width);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pose.pitch, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(pose.roll, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d t(pose.x, pose.y, pose.z);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double inf = std::numeric_limits<double>::infinity();
  for (int u = 0; u < s.height; ++u) {
    for (int v = 0; v < width; ++v) {
      const size_t i = size_t(u) * width + v;
      const Eigen::Vector3d dir = R * (lut.direction.row(i).transpose().cast<double>() * 1000.0);
      const Eigen::Vector3d o = R * lut.offset.row(i).transpose().cast<double>() + t;
      double best = inf;
      Label lab = kNone;
      auto consider = [&](double tt, Label l) {
        if (tt > 1e-6 && tt < best) {
          best = tt;
          lab = l;
        }
      };
      if (room.ceiling && room.ramp.ceiling_follows && room.ramp.x1 > room.ramp.x0)
        consider(hit_ramp_ceiling(room.ramp, room.height, o, dir), kCeiling);
      else if (dir.z() > 0 && room.ceiling)
        consider((room.height - o.z()) / dir.z(), kCeiling);
      if (room.ramp.x1 > room.ramp.x0)
        consider(hit_ramp_floor(room.ramp, o, dir), kFloor);
      else if (dir.z() < 0)
        consider(-o.z() / dir.z(), kFloor);
      if (dir.x() > 0) consider((room.half_x - o.x()) / dir.x(), kWall);
      if (dir.x() < 0) consider((-room.half_x - o.x()) / dir.x(), kWall);
      if (dir.y() > 0) consider((room.half_y - o.y()) / dir.y(), kWall);
      if (dir.y() < 0) consider((-room.half_y - o.y()) / dir.y(), kWall);
      // Walls only count inside the room's height (open sky above when there is no ceiling).
      if (lab == kWall) {
        const double zh = o.z() + best * dir.z();
        if (zh > (room.wall_top > 0 ? room.wall_top : room.height)) {
          best = inf;
          lab = kNone;
        }
      }
      for (const Box& b : room.boxes) consider(hit_box(o, dir, b), b.label);
      const double r = best + noise * gauss(rng);
      const bool drop = uni(rng) < dropout;
      if (!std::isfinite(best) || drop || r <= 0.3 || r > 120.0) continue;
      // Range is measured from the beam origin: range along `dir` from the lidar origin (Ouster model:
      // p = r * d + offset, so `best` is already that r).
      s.range_mm[i] = uint32_t(std::lround(r * 1000.0));
      out.label[i] = lab;
    }
  }
  return out;
}

}  // namespace fploc::seg::synth
