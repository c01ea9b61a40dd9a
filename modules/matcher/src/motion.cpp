#include <cmath>

#include "fploc/matcher/types.h"

namespace fploc::matcher {
namespace {
// cos, sin, sin(th)/th, (1 - cos(th))/th for the small angles of one sweep: series to 7th order for
// |th| < 0.2 (error < 1e-11), std:: else.
inline void small_angle(double th, double* c, double* s, double* a, double* b) {
  if (std::abs(th) < 0.2) {
    const double t2 = th * th;
    *a = 1 - t2 / 6 * (1 - t2 / 20 * (1 - t2 / 42));
    *b = th / 2 * (1 - t2 / 12 * (1 - t2 / 30));
    *c = 1 - th * *b;
    *s = th * *a;
  } else {
    *c = std::cos(th);
    *s = std::sin(th);
    *a = *s / th;
    *b = (1 - *c) / th;
  }
}
}  // namespace

Pose2 exp_twist(const Twist2& v, double t) {
  const double th = v.w * t;
  double c, s, a, b;
  small_angle(th, &c, &s, &a, &b);
  return {(a * v.vx - b * v.vy) * t, (b * v.vx + a * v.vy) * t, th};
}

Twist2 log_twist(const Pose2& p, const Pose2& q, double dt) {
  if (!(dt > 0)) return {};
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  const double dx = q.x - p.x, dy = q.y - p.y;
  // Relative pose in p's frame.
  const double rx = c * dx + s * dy, ry = -s * dx + c * dy, th = wrap_angle(q.yaw - p.yaw);
  double cc, ss, a, b;
  small_angle(th, &cc, &ss, &a, &b);
  // Invert V = [a -b; b a]: V^-1 = [a b; -b a] / (a^2 + b^2).
  const double d = a * a + b * b;
  return {(a * rx + b * ry) / d / dt, (-b * rx + a * ry) / d / dt, th / dt};
}


void deskew(const FeatureFrame& raw, const Twist2& v, double t_ref, FeatureFrame* out) {
  if (out != &raw) {
    out->utime = raw.utime;
    out->scan_seq = raw.scan_seq;
    out->roll = raw.roll;
    out->pitch = raw.pitch;
    out->z = raw.z;
    out->roll_pitch_sigma = raw.roll_pitch_sigma;
    out->z_sigma = raw.z_sigma;
    out->sweep_yaw_rate = raw.sweep_yaw_rate;
    out->points = raw.points;
  }
  for (auto& fp : out->points) {
    const double t = double(fp.t) - t_ref, th = v.w * t;
    if (t == 0) continue;
    // exp_twist(v, t): rotation th, translation V(th) v t with V = [a -b; b a].
    double c, s, a, b;
    small_angle(th, &c, &s, &a, &b);
    const double tx = (a * v.vx - b * v.vy) * t, ty = (b * v.vx + a * v.vy) * t;
    const Eigen::Vector2d p = fp.p;
    fp.p = {c * p.x() - s * p.y() + tx, s * p.x() + c * p.y() + ty};
  }
}

double mean_time(const FeatureFrame& f) {
  double s = 0;
  for (const auto& p : f.points) s += double(p.t);
  return f.points.empty() ? 0.0 : s / double(f.points.size());
}

double sweep_duration(const FeatureFrame& f) {
  double m = 0;
  for (const auto& p : f.points) m = std::max(m, double(std::abs(p.t)));
  return m;
}

}  // namespace fploc::matcher