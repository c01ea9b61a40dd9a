#include "fploc/localizer/floor_tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace fploc::localizer {

namespace {

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

double dist_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

FloorTracker::FloorTracker(std::shared_ptr<const Building> building, int initial_floor, FloorTrackerConfig cfg)
    : building_(std::move(building)), cfg_(cfg), floor_(initial_floor), vertical_(cfg.vertical) {
  if (!building_ || building_->floors.empty()) throw std::invalid_argument("FloorTracker: a building with floors is needed");
  if (initial_floor < 0 || size_t(initial_floor) >= building_->floors.size())
    throw std::invalid_argument("FloorTracker: no floor " + std::to_string(initial_floor) + " in " + building_->source);
}

const std::string& FloorTracker::floor_name() const { return building_->floors[size_t(floor_)].name; }

void FloorTracker::search_disc(const std::vector<Eigen::Vector2d>& poly, double margin, Eigen::Vector2d* c, double* r) {
  Eigen::Vector2d m = Eigen::Vector2d::Zero();
  for (const auto& p : poly) m += p;
  if (!poly.empty()) m /= double(poly.size());
  double rr = 0;
  for (const auto& p : poly) rr = std::max(rr, (p - m).norm());
  *c = m;
  *r = rr + margin;
}

bool FloorTracker::near(const FloorConnection& c, const Eigen::Vector2d& p) const {
  if (c.contains(p)) return true;
  for (size_t i = 0; i < c.polygon.size(); ++i)
    if (dist_to_segment(p, c.polygon[i], c.polygon[(i + 1) % c.polygon.size()]) <= cfg_.connection_margin_m) return true;
  return false;
}

void FloorTracker::add_imu(int64_t utime, const Eigen::Vector3d& accel) {
  if (!accel.allFinite()) return;
  vertical_.add(utime, accel);
  if (!have_f_) {
    f_lp_ = accel;
    have_f_ = true;
  } else if (utime > last_imu_utime_) {
    const double dt = (utime - last_imu_utime_) * 1e-6;
    f_lp_ += (accel - f_lp_) * std::min(1.0, dt / cfg_.tilt_lowpass_s);
  }
  last_imu_utime_ = std::max(last_imu_utime_, utime);
}

void FloorTracker::set_floor(int floor, const std::string& reason) {
  if (floor < 0 || size_t(floor) >= building_->floors.size())
    throw std::invalid_argument("FloorTracker: no floor " + std::to_string(floor) + " in " + building_->source);
  floor_ = floor;
  z_offset_ = 0;
  in_climb_area_ = false;
  confirm_ = 0;
  confirm_to_ = -1;
  vertical_.reset();
  text_ = "on '" + floor_name() + "': " + reason;
}

FloorSwitch FloorTracker::make_switch(int to, const FloorConnection& via, const std::string& reason) {
  FloorSwitch s;
  s.from = floor_;
  s.to = to;
  s.from_name = floor_name();
  s.to_name = building_->floors[size_t(to)].name;
  s.via = via;
  s.reason = reason;
  search_disc(via.polygon, cfg_.connection_margin_m, &s.search_center, &s.search_radius_m);
  floor_ = to;
  confirm_ = 0;
  confirm_to_ = -1;
  text_ = "floor '" + s.from_name + "' -> '" + s.to_name + "': " + reason;
  return s;
}

std::optional<FloorSwitch> FloorTracker::check_lift(const FloorObservation& o, const VerticalRide& ride) {
  const Eigen::Vector2d p(o.pose.x, o.pose.y);
  const double e0 = building_->floors[size_t(floor_)].elevation;
  const std::string h = fmt("%+.2f m", ride.height_m);
  const std::string dur = fmt("%.1f s", (ride.end_utime - ride.start_utime) * 1e-6);
  if (std::abs(ride.height_m) < cfg_.lift_min_height_m) {
    text_ = "lift ride of " + h + " in " + dur + ": no floor change (below " + fmt("%.2f m", cfg_.lift_min_height_m) + ")";
    return std::nullopt;
  }
  // Floors reachable through lift connections near the robot (a lift serving several floors has one
  // connection per pair), with the connection of the last hop.
  std::vector<int> via(building_->floors.size(), -1);
  std::vector<bool> seen(building_->floors.size(), false);
  std::vector<int> todo{floor_};
  seen[size_t(floor_)] = true;
  while (!todo.empty()) {
    const int f = todo.back();
    todo.pop_back();
    const std::string& name = building_->floors[size_t(f)].name;
    for (size_t k = 0; k < building_->connections.size(); ++k) {
      const auto& c = building_->connections[k];
      if (c.kind != ConnectionKind::kLift || !near(c, p)) continue;
      const std::string other = c.from_floor == name ? c.to_floor : c.to_floor == name ? c.from_floor : "";
      const int oi = other.empty() ? -1 : building_->floor_index(other);
      if (oi < 0 || seen[size_t(oi)]) continue;
      seen[size_t(oi)] = true;
      via[size_t(oi)] = int(k);
      todo.push_back(oi);
    }
  }
  int best = -1;
  double best_err = 0;
  for (size_t f = 0; f < via.size(); ++f) {
    if (via[f] < 0) continue;
    const double err = std::abs(ride.height_m - (building_->floors[f].elevation - e0));
    if (best < 0 || err < best_err) best = int(f), best_err = err;
  }
  if (best < 0) {
    text_ = "lift ride of " + h + " in " + dur + " but no lift connection of '" + floor_name() + "' here: staying";
    return std::nullopt;
  }
  const BuildingFloor& bf = building_->floors[size_t(best)];
  const double de = bf.elevation - e0;
  const std::string plan = ride_frames_ > 0
                               ? fmt("%.0f %%", 100 * ride_inliers_sum_ / ride_frames_) + " of the points during the ride"
                               : std::string("no frame during the ride");
  if (best_err > cfg_.lift_tolerance_fraction * std::abs(de)) {
    text_ = "lift ride of " + h + " in " + dur + " matches no floor (nearest '" + bf.name + "' at " +
            fmt("%+.2f m", de) + "): staying on '" + floor_name() + "'";
    return std::nullopt;
  }
  const std::string reason = "lift '" + building_->connections[size_t(via[size_t(best)])].name + "': IMU vertical motion " +
                             h + " in " + dur + " (floor '" + bf.name + "' is " + fmt("%+.2f m", de) + " from '" +
                             floor_name() + "'); the plan of '" + floor_name() + "' matched " + plan + " (before " +
                             fmt("%.0f %%", 100 * before_inliers_) + ")";
  return make_switch(best, building_->connections[size_t(via[size_t(best)])], reason);
}

std::optional<FloorSwitch> FloorTracker::update(const FloorObservation& o) {
  const Eigen::Vector2d p(o.pose.x, o.pose.y);
  const std::string& name = floor_name();
  const double e0 = building_->floors[size_t(floor_)].elevation;
  bool near_lift = false, near_climb = false;
  for (const auto& c : building_->connections) {
    if (c.from_floor != name && c.to_floor != name) continue;
    if (!near(c, p)) continue;
    (c.kind == ConnectionKind::kLift ? near_lift : near_climb) = true;
  }

  // ---- lift: the IMU's vertical motion while standing in a lift area (driving: no ride; the integration
  // restarts, so slow drifts of |f| while driving never add up to a "ride")
  double speed = 0;
  if (have_lift_prev_ && o.utime > lift_prev_utime_)
    speed = std::hypot(o.pose.x - lift_prev_.x, o.pose.y - lift_prev_.y) / ((o.utime - lift_prev_utime_) * 1e-6);
  have_lift_prev_ = true;
  lift_prev_utime_ = o.utime;
  lift_prev_ = o.pose;
  const bool still = speed <= cfg_.lift_max_speed_mps;
  const bool in_lift = still && (near_lift || (in_lift_ && vertical_.riding()));
  if (!in_lift) vertical_.reset();
  in_lift_ = in_lift;
  const auto ride = vertical_.take_ride();
  if (vertical_.riding() || ride) {
    ride_inliers_sum_ += std::clamp(o.inlier_ratio, 0.0, 1.0);
    ++ride_frames_;
  }
  if (ride && in_lift) {
    auto s = check_lift(o, *ride);
    ride_inliers_sum_ = 0;
    ride_frames_ = 0;
    if (s) {
      in_climb_area_ = false;
      have_prev_ = false;
      return s;
    }
  }
  if (!vertical_.riding() && !ride) {
    ride_inliers_sum_ = 0;
    ride_frames_ = 0;
    before_inliers_ += (std::clamp(o.inlier_ratio, 0.0, 1.0) - before_inliers_) * 0.2;
  }

  // ---- flat floor: the nominal sensor height, and the offset carried since a ramp/stairs switch
  if (!near_lift && !near_climb && o.z_known && !vertical_.riding()) {
    if (z_offset_ != 0 && z0_ && std::abs(o.z - *z0_) < cfg_.z_offset_drop_m) {
      text_ = "on '" + name + "': the segmenter's z " + fmt("%.2f m", o.z) + " is relative to this floor again (offset " +
              fmt("%+.2f m", z_offset_) + " dropped)";
      z_offset_ = 0;
    }
    const double zf = floor_z(o.z);
    if (!z0_ || std::abs(zf - *z0_) < cfg_.z_offset_drop_m) {
      flat_z_.push_back(zf);
      while (int(flat_z_.size()) > cfg_.nominal_z_frames) flat_z_.pop_front();
      if (flat_z_.size() >= 10) z0_ = median(std::vector<double>(flat_z_.begin(), flat_z_.end()));
    }
  }

  // ---- stairs / ramp: the climb since entering the area
  if (!near_climb) {
    in_climb_area_ = false;
    tilt_climb_ = 0;
    tilt_valid_ = false;
    confirm_ = 0;
    have_prev_ = true;
    prev_pose_ = o.pose;
    return std::nullopt;
  }
  if (!in_climb_area_) {
    in_climb_area_ = true;
    enter_elevation_ = e0;
    tilt_climb_ = 0;
    tilt_valid_ = false;
    switched_in_area_ = false;
  } else if (have_prev_) {
    // Attitude: the IMU's gravity direction, else the frame's own roll/pitch.
    std::optional<std::pair<double, double>> rp;
    if (have_f_ && f_lp_.norm() > 1) rp = {std::atan2(f_lp_.y(), f_lp_.z()), std::atan2(-f_lp_.x(), std::hypot(f_lp_.y(), f_lp_.z()))};
    else if (o.roll_pitch_known) rp = {o.roll, o.pitch};
    if (rp && std::abs(rp->first) < cfg_.max_tilt_rad && std::abs(rp->second) < cfg_.max_tilt_rad) {
      const double dx = o.pose.x - prev_pose_.x, dy = o.pose.y - prev_pose_.y;
      const double c = std::cos(o.pose.yaw), s = std::sin(o.pose.yaw);
      const double fwd = c * dx + s * dy, side = -s * dx + c * dy;
      // The floor's normal in the yaw-levelled frame is the sensor's z axis: Ry(pitch) Rx(roll) e_z.
      const double cr = std::cos(rp->first), sr = std::sin(rp->first), cp = std::cos(rp->second), sp = std::sin(rp->second);
      const Eigen::Vector3d n(sp * cr, -sr, cp * cr);
      tilt_climb_ += -(n.x() * fwd + n.y() * side) / n.z();
      tilt_valid_ = true;
    }
  }
  have_prev_ = true;
  prev_pose_ = o.pose;

  const std::optional<double> z_climb =
      o.z_known && z0_ ? std::optional<double>(floor_z(o.z) - *z0_) : std::nullopt;
  int cand = -1;
  const FloorConnection* cand_via = nullptr;
  std::string cue;
  for (const auto& c : building_->connections) {
    if (c.kind == ConnectionKind::kLift || (c.from_floor != name && c.to_floor != name) || !near(c, p)) continue;
    const int oi = building_->floor_index(c.from_floor == name ? c.to_floor : c.from_floor);
    if (oi < 0 || oi == floor_) continue;
    const double de = building_->floors[size_t(oi)].elevation - e0;
    if (std::abs(de) < 1e-6) continue;
    const double need = cfg_.switch_fraction + (switched_in_area_ ? cfg_.switch_back_margin : 0.0);
    const auto past = [&](double climb) { return climb / de > need; };
    // The tilt's climb is counted from where the robot entered the area (possibly on another floor).
    const double tilt_here = enter_elevation_ + tilt_climb_ - e0;
    const std::string to = fmt("%+.2f m", de);
    if (z_climb && past(*z_climb))
      cand = oi, cand_via = &c, cue = "z " + fmt("%+.2f m", *z_climb) + " above the nominal height";
    else if (tilt_valid_ && past(tilt_here))
      cand = oi, cand_via = &c, cue = "IMU tilt x travel " + fmt("%+.2f m", tilt_climb_) + " since entering";
    if (cand == oi) {
      cue = std::string(to_string(c.kind)) + " '" + c.name + "': climbed past " + fmt("%.0f %%", 100 * cfg_.switch_fraction) +
            " of the way to '" + building_->floors[size_t(oi)].name + "' (" + to + "): " + cue;
      break;
    }
  }
  if (cand < 0) {
    confirm_ = 0;
    return std::nullopt;
  }
  confirm_ = cand == confirm_to_ ? confirm_ + 1 : 1;
  confirm_to_ = cand;
  if (confirm_ < cfg_.confirm_frames) return std::nullopt;
  const double de = building_->floors[size_t(cand)].elevation - e0;
  const FloorConnection via = *cand_via;
  auto s = make_switch(cand, via, cue);
  // Heights relative to the new floor from now on. The segmenter's z keeps its old reference only when it
  // followed the climb (a ceiling-based z under one ceiling); a z from the ramp's own surface did not move.
  if (z_climb && *z_climb / de > 0.5 * cfg_.switch_fraction) z_offset_ += de;
  switched_in_area_ = true;
  return s;
}

}  // namespace fploc::localizer
