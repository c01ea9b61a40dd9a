#include "fploc/sim/journey.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fploc::sim {

LiftProfile::LiftProfile(double r, const LiftConfig& c) : rise(r), accel(c.accel_mps2) {
  const double d = std::abs(r);
  // a(t) = A sin^2(pi t / Ta) up to v = A Ta / 2, covering v^2 / A; the same down.
  v = std::min(c.v_max, std::sqrt(accel * d / 2));
  t_acc = 2 * v / accel;
  t_cruise = v > 0 ? (d - 2 * v * v / accel) / v : 0;
  t_cruise = std::max(0.0, t_cruise);
}

double LiftProfile::z(double t) const {
  if (t_acc <= 0) return 0;
  const double sign = rise < 0 ? -1 : 1, d = std::abs(rise);
  const double w = 2 * M_PI / t_acc;
  auto acc_part = [&](double tt) { return 0.5 * accel * (0.5 * tt * tt + (std::cos(w * tt) - 1) / (w * w)); };
  const double z_acc = acc_part(t_acc);
  double z;
  if (t <= 0) z = 0;
  else if (t <= t_acc) z = acc_part(t);
  else if (t <= t_acc + t_cruise) z = z_acc + v * (t - t_acc);
  else if (t < duration()) z = d - acc_part(duration() - t);
  else z = d;
  return sign * z;
}

double LiftProfile::accel_at(double t) const {
  if (t <= 0 || t >= duration() || t_acc <= 0) return 0;
  const double sign = rise < 0 ? -1 : 1;
  const double s = std::sin(M_PI * std::fmod(t, t_acc) / t_acc);
  if (t < t_acc) return sign * accel * s * s;
  if (t <= t_acc + t_cruise) return 0;
  const double tt = duration() - t;
  const double s2 = std::sin(M_PI * tt / t_acc);
  return -sign * accel * s2 * s2;
}

int Journey::Leg::floor_at_s(double s) const {
  int f = floor0;
  for (const auto& [s0, fl] : switches) {
    if (s < s0) break;
    f = fl;
  }
  return f;
}

Journey::Journey(const Building& b, const std::vector<JourneyLeg>& legs, SpeedSpec speed, uint64_t seed,
                 std::vector<FloorGround> grounds, LiftConfig lift)
    : b_(b), grounds_(std::move(grounds)), lift_(lift) {
  if (legs.empty()) throw std::runtime_error("journey: no legs");
  if (grounds_.size() != b_.floors.size()) throw std::runtime_error("journey: one ground per floor needed");
  double t = 0, s_total = 0;
  for (size_t i = 0; i < legs.size(); ++i) {
    Leg leg;
    leg.floor0 = b_.floor_index(legs[i].floor);
    if (leg.floor0 < 0 || legs[i].floor.empty())
      throw std::runtime_error(b_.source + ": journey leg " + std::to_string(i) + ": no floor '" + legs[i].floor + "'");
    MotionConfig mc;
    mc.preroll_s = i == 0 ? 1.0 : 0.0;
    mc.postroll_s = i + 1 == legs.size() ? 1.0 : 0.0;
    mc.s0 = s_total;
    mc.t0 = t;
    // Where the path changes floor: crossing the middle of a ramp between its floor and another.
    std::vector<std::string> ramp_names;
    {
      const Motion probe(legs[i].control, false, speed, 0, seed, mc);
      int f = leg.floor0;
      for (double s = 0; s <= probe.length(); s += 0.02) {
        const Eigen::Vector2d p = probe.point_at(s);
        for (const auto& in : grounds_[size_t(f)].inclines) {
          if (in.kind != ConnectionKind::kRamp || !in.contains(p)) continue;
          const double tau = in.tau(p);
          int nf = f;
          if (f == in.from_floor && tau > 0.5) nf = in.to_floor;
          else if (f == in.to_floor && tau < 0.5) nf = in.from_floor;
          if (nf != f) {
            leg.switches.emplace_back(s, nf);
            ramp_names.push_back(in.name);
            f = nf;
            break;
          }
        }
      }
    }
    const size_t li = i;
    mc.ground = [this, li](double s, const Eigen::Vector2d& p) {
      const int f = legs_[li].floor_at_s(s);
      const FloorGround& g = grounds_[size_t(f)];
      return g.elevation + g.wheel_at(p);
    };
    leg.t_start = t;
    legs_.push_back(std::move(leg));
    legs_.back().motion = std::make_unique<Motion>(legs[i].control, false, speed, 0, seed, mc);
    const Motion& m = *legs_.back().motion;
    // The ramp switch times: when the leg's arc length passes the switch point.
    int prev = legs_.back().floor0;
    for (size_t k = 0; k < legs_.back().switches.size(); ++k) {
      const auto [s_sw, nf] = legs_.back().switches[k];
      double lo = 0, hi = m.duration();
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (m.s_at(mid) < s_sw ? lo : hi) = mid;
      }
      changes_.push_back({t + hi, prev, nf, "ramp " + ramp_names[k]});
      prev = nf;
    }
    s_total += m.length();
    t += m.duration();
    if (i + 1 < legs.size()) {
      // A lift ride from where this leg ends to the next leg's floor.
      const int from = legs_.back().floor_at_s(m.length());
      const int to = b_.floor_index(legs[i + 1].floor);
      const Eigen::Vector2d end = m.point_at(m.length());
      Ride r;
      for (size_t c = 0; c < b_.connections.size(); ++c) {
        const auto& con = b_.connections[c];
        if (con.kind != ConnectionKind::kLift || !con.contains(end)) continue;
        const int cf = b_.floor_index(con.from_floor), ct = b_.floor_index(con.to_floor);
        if ((cf == from && ct == to) || (cf == to && ct == from)) r.lift = int(c);
      }
      if (r.lift < 0)
        throw std::runtime_error(b_.source + ": journey leg " + std::to_string(i) + " ends at (" + std::to_string(end.x()) +
                                 ", " + std::to_string(end.y()) + ") on floor '" + b_.floors[size_t(from)].name +
                                 "', not inside a lift to floor '" + legs[i + 1].floor + "'");
      r.from = from;
      r.to = to;
      r.t_arrive = t;
      r.t_move = t + lift_.doors_s;
      r.profile = LiftProfile(b_.floors[size_t(to)].elevation - b_.floors[size_t(from)].elevation, lift_);
      r.z_from = b_.floors[size_t(from)].elevation;
      changes_.push_back({r.t_move + r.profile.duration(), from, to, "lift " + b_.connections[size_t(r.lift)].name});
      t = r.t_move + r.profile.duration() + lift_.doors_s;
      rides_.push_back(r);
    }
  }
  duration_ = t;
  std::sort(changes_.begin(), changes_.end(), [](const FloorChange& a, const FloorChange& c) { return a.t < c.t; });
}

double Journey::moving_time() const {
  double s = 0;
  for (const auto& l : legs_) s += l.motion->moving_time();
  return s;
}

double Journey::length() const {
  double s = 0;
  for (const auto& l : legs_) s += l.motion->length();
  return s;
}

double Journey::max_speed() const {
  double v = 0;
  for (const auto& l : legs_) v = std::max(v, l.motion->max_speed());
  return v;
}

int Journey::start_floor() const { return legs_.front().floor0; }

Eigen::Isometry3d Journey::pose(double t) const {
  t = std::clamp(t, 0.0, duration_);
  for (size_t i = 0; i < legs_.size(); ++i) {
    const Leg& l = legs_[i];
    const double te = l.t_start + l.motion->duration();
    if (t <= te || i + 1 == legs_.size()) return l.motion->pose(t - l.t_start);
    const Ride& r = rides_[i];
    if (t < legs_[i + 1].t_start) {
      Eigen::Isometry3d p = l.motion->pose(l.motion->duration());
      p.translation().z() += r.profile.z(t - r.t_move);
      return p;
    }
  }
  return legs_.back().motion->pose(t - legs_.back().t_start);
}

std::vector<Eigen::Vector2d> Journey::sample_path(double ds) const {
  std::vector<Eigen::Vector2d> out;
  for (const auto& l : legs_) {
    const auto p = l.motion->sample_path(ds);
    out.insert(out.end(), p.begin(), p.end());
  }
  return out;
}

std::vector<Eigen::Vector2d> Journey::sample_path_on_floor(int floor, double ds) const {
  std::vector<Eigen::Vector2d> out;
  for (const auto& l : legs_)
    for (double s = 0; s <= l.motion->length(); s += ds)
      if (l.floor_at_s(s) == floor) out.push_back(l.motion->point_at(s));
  return out;
}

int Journey::floor_at(double t) const {
  int f = legs_.front().floor0;
  for (const auto& c : changes_) {
    if (t < c.t) break;
    f = c.to;
  }
  return f;
}

bool Journey::in_closed_lift(double t, int* lift, double* car_floor_z) const {
  for (const auto& r : rides_) {
    const double closed0 = r.t_arrive + 0.5 * lift_.doors_s, closed1 = r.t_move + r.profile.duration() + 0.5 * lift_.doors_s;
    if (t >= closed0 && t < closed1) {
      if (lift) *lift = r.lift;
      if (car_floor_z) *car_floor_z = r.z_from + r.profile.z(t - r.t_move);
      return true;
    }
  }
  return false;
}

std::string Journey::state_at(double t) const {
  for (const auto& r : rides_) {
    if (t >= r.t_move && t < r.t_move + r.profile.duration()) return "lift-moving";
    if (in_closed_lift(t)) {
      const double closed0 = r.t_arrive + 0.5 * lift_.doors_s, closed1 = r.t_move + r.profile.duration() + 0.5 * lift_.doors_s;
      if (t >= closed0 && t < closed1) return "lift-closed";
    }
    if (t >= r.t_arrive && t < r.t_move + r.profile.duration() + lift_.doors_s) return "lift";
  }
  for (size_t i = 0; i < legs_.size(); ++i) {
    const Leg& l = legs_[i];
    if (t < l.t_start || t > l.t_start + l.motion->duration()) continue;
    const double s = l.motion->s_at(t - l.t_start);
    const Eigen::Vector2d p = l.motion->point_at(s);
    for (const auto& in : grounds_[size_t(l.floor_at_s(s))].inclines)
      if (in.contains(p)) return "ramp";
    return "drive";
  }
  return "drive";
}

}  // namespace fploc::sim
