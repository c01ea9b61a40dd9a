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
  try {
    inclines_ = building_inclines(*building_);
  } catch (const std::exception& e) {
    // Without the incline geometry the pose's z on a ramp is the segmenter's (the climb cues still work).
    text_ = std::string("ramps/stairs without geometry: ") + e.what();
  }
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
  ride_active_ = false;
  mismatch_ = 0;
  probe_.clear();
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

std::vector<int> FloorTracker::lift_reachable(const Eigen::Vector2d& p, std::vector<int>* via_out) const {
  // Floors reachable through lift connections near p (a lift serving several floors has one connection per
  // pair), with the connection of the last hop.
  std::vector<int> via(building_->floors.size(), -1);
  std::vector<bool> seen(building_->floors.size(), false);
  std::vector<int> todo{floor_}, out;
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
      out.push_back(oi);
    }
  }
  *via_out = std::move(via);
  return out;
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
  std::vector<int> via;
  lift_reachable(p, &via);
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
  auto s = update_floor(o);
  resolve_z(o, s);
  check_mismatch(o, s.has_value());
  last_utime_ = o.utime;
  return s;
}

double FloorTracker::pose_z_sigma(double segmenter_sigma) const {
  if (z_gated_) return std::max(segmenter_sigma, cfg_.z_gated_sigma_m);
  if (!(ride_active_ && vertical_.riding())) return segmenter_sigma;
  // The double-integrated accelerometer: a residual acceleration error grows as 0.5 a t^2.
  const double t = std::max<int64_t>(0, vertical_.last_utime() - vertical_.ride_start_utime()) * 1e-6;
  const double r = std::min(cfg_.max_ride_z_sigma_m, 0.5 * cfg_.ride_accel_sigma_mps2 * t * t);
  return std::sqrt(segmenter_sigma * segmenter_sigma + r * r);
}

std::optional<FloorTracker::InclineAt> FloorTracker::incline_under(const Eigen::Vector2d& p) const {
  const double e = building_->floors[size_t(floor_)].elevation;
  for (const auto& in : inclines_) {
    if ((in.from_floor != floor_ && in.to_floor != floor_) || !in.contains(p)) continue;
    const double run = (in.head - in.foot).norm();
    return InclineAt{std::clamp(in.z_at(p), std::min(in.z_foot, in.z_head), std::max(in.z_foot, in.z_head)) - e,
                     std::hypot(run, in.z_head - in.z_foot) / run,
                     std::string(to_string(in.kind)) + " '" + in.name + "' surface"};
  }
  return std::nullopt;
}

void FloorTracker::resolve_z(const FloorObservation& o, const std::optional<FloorSwitch>& s) {
  const BuildingFloor& fl = building_->floors[size_t(floor_)];
  const double e = fl.elevation;
  const double before = pose_z_;
  // Lift: the sensor stands on the car's floor; its height is the nominal one plus the IMU's vertical
  // motion since the ride started (the segmenter sees the car, whatever its ceiling).
  if (in_lift_ && vertical_.riding()) {
    if (!ride_active_) {
      ride_active_ = true;
      // The height the segmenter measured last while it agreed with the building (in the lift before the
      // doors closed: the sensor's height varies along a path), else the nominal one.
      ride_base_ = have_good_h_ && o.utime - good_h_utime_ < 15'000'000 ? good_h_ : z0_ ? *z0_ : have_h_ ? h_ : o.z_known ? o.z : 0.0;
    }
    // The IMU's height at the frame's attitude time (its samples run ahead of the frame by up to a sweep).
    const double ahead = std::clamp((vertical_.last_utime() - o.utime) * 1e-6 - o.attitude_t, 0.0, 0.3);
    h_ = ride_base_ + vertical_.height() - vertical_.velocity() * ahead;
    have_h_ = true;
    z_gated_ = false;
    // Above the car's floor the sensor stays where it stood: that is the last good height on arrival (the
    // segmenter may still see only the car, whose ceiling it has not learned).
    above_ = ride_base_;
    above_utime_ = o.utime;
    have_above_ = true;
    pose_z_ = e + h_;
    z_source_ = "lift ride (IMU)";
    return;
  }
  const bool ride_ended = ride_active_;
  ride_active_ = false;
  const Eigen::Vector2d p(o.pose.x, o.pose.y);
  const auto incline = incline_under(p);
  // A z the segmenter only predicted (its last measurement, held while it sees no plane: sigma above what the
  // building's own prediction has) does not follow a climb; on a ramp or stairs the surface under the sensor
  // does, so there the last good height above that surface is kept, as for no z at all.
  const bool predicted = o.z_known && o.z_sigma > cfg_.z_gated_sigma_m;
  if (!o.z_known || (predicted && incline)) {
    // Held: the same absolute z (a switch changes the floor, not where the sensor is), or on an incline the
    // last good height above its surface.
    if (incline && have_above_ && o.utime - above_utime_ < int64_t(cfg_.z_hold_s * 1e6)) {
      h_ = incline->g + above_;
      have_h_ = true;
      pose_z_ = e + h_;
      z_source_ = "held (" + fmt("%.2f m", above_) + " above " + incline->name + ")";
      return;
    }
    if (!o.z_known) {
      if (have_h_) h_ = pose_z_ - e;
      else pose_z_ = e + o.z;
      z_source_ = "held";
      return;
    }
  }
  struct Ref {
    int kind;
    double r;  // the segmenter's zero above the current floor's level
    std::string name;
    double scale = 1;  // a height measured across an incline's plane: vertically it is z / cos(slope)
  };
  std::vector<Ref> refs{{0, 0.0, "floor '" + fl.name + "'"}};
  const double g = incline ? incline->g : 0.0, inv_cos = incline ? incline->inv_cos : 1.0;
  if (incline) refs.push_back({1, g, incline->name, inv_cos});
  if (z_offset_ != 0) refs.push_back({2, -z_offset_, "floor left (" + fmt("%+.2f m", -z_offset_) + ")"});
  size_t best = 0;
  // The sensor's nominal height above the surface under it, vertically: z0 on flat floor; on an incline
  // between z0 (a mount that keeps the sensor's height, as the simulator's) and z0 / cos (a rigid mast
  // across the plane): the middle, with half the difference as extra tolerance below.
  const double want = z0_ ? *z0_ * 0.5 * (1 + inv_cos) + g : 0.0;
  const auto height = [&](const Ref& r) { return o.z * r.scale + r.r; };
  if (z0_) {
    // The reference that puts the sensor nearest its nominal height above the surface under it; the one in
    // use is kept unless another is better by the hysteresis.
    const auto res = [&](const Ref& r) { return std::abs(height(r) - want); };
    for (size_t i = 1; i < refs.size(); ++i)
      if (res(refs[i]) < res(refs[best])) best = i;
    for (size_t i = 0; i < refs.size(); ++i)
      if (refs[i].kind == z_ref_kind_ && res(refs[i]) <= res(refs[best]) + cfg_.z_reference_hysteresis_m) best = i;
  }
  z_ref_kind_ = refs[best].kind;
  h_ = height(refs[best]);
  have_h_ = true;
  z_source_ = "segmenter (above " + refs[best].name + ")";
  // Consistency with the building: the sensor stands z0 above the surface under it (a floor, an incline,
  // a lift car at rest). A segmenter's z further off than the gate (a ceiling of another height than it
  // learned, the car's ceiling, ...) is not used: the prediction, with a grown sigma, and said.
  const bool was_gated = z_gated_;
  z_gated_ = false;
  if (z0_ && std::abs(h_ - want) > cfg_.z_gate_m + *z0_ * 0.5 * (inv_cos - 1)) {
    const double off = h_ - want;
    // The prediction: the sensor's last good height above the surface under it (the tripod's height changes
    // slowly along the path) when it is recent, else the nominal one.
    const bool recent = have_above_ && o.utime - above_utime_ < int64_t(cfg_.z_hold_s * 1e6);
    h_ = recent ? g + above_ : want;
    z_gated_ = true;
    z_source_ = "building: " + (recent ? "last good height " + fmt("%.2f m", above_) : "nominal height " + fmt("%.2f m", *z0_)) +
                " above " + (refs.size() > 1 && g != 0 ? refs[1].name : refs[0].name) + " (the segmenter's z is " +
                fmt("%+.2f m", off) + " off)";
    if (!was_gated) text_ = "z: " + z_source_;
  } else if (have_above_ && o.utime - above_utime_ < int64_t(cfg_.z_step_window_s * 1e6) &&
             std::abs(h_ - g - above_) > cfg_.z_step_gate_m) {
    // A step in the height above the surface under the sensor since the last good frame (the segmenter took
    // another surface for the one under the robot, a ramp's kink for a floor, ...): not used until frames in
    // a row agree on the new height.
    const double a = h_ - g;
    step_frames_ = step_frames_ > 0 && std::abs(a - step_above_) <= cfg_.z_step_gate_m ? step_frames_ + 1 : 1;
    step_above_ = a;
    if (step_frames_ < cfg_.z_step_confirm_frames) {
      h_ = g + above_;
      z_gated_ = true;
      z_source_ = "building: last good height " + fmt("%.2f m", above_) + " above " + (g != 0 ? refs[1].name : refs[0].name) +
                  " (the segmenter's jumped " + fmt("%+.3f m", a - above_) + ")";
    } else {
      step_frames_ = 0;
    }
  } else {
    step_frames_ = 0;
    if (was_gated)
      text_ = "z: the segmenter's again (" + fmt("%.2f m", h_ - (refs[best].kind == 1 ? g : 0.0)) + " above " + refs[best].name + ")";
  }
  if (!z_gated_) {
    above_ = h_ - g;
    above_utime_ = o.utime;
    have_above_ = true;
  }
  if (!z_gated_ && g == 0) {
    good_h_ = h_;
    good_h_utime_ = o.utime;
    have_good_h_ = true;
  }
  pose_z_ = e + h_;
  if ((s && s->via.kind == ConnectionKind::kLift) || ride_ended)
    text_ += "; z " + fmt("%.2f m", before) + " -> " + fmt("%.2f m", pose_z_) + " (the IMU's ride ended: '" + fl.name +
             "' at " + fmt("%.2f m", e) + " + the segmenter's " + fmt("%.2f m", h_) + ")";
}

void FloorTracker::check_mismatch(const FloorObservation& o, bool switched) {
  probe_.clear();
  const Eigen::Vector2d p(o.pose.x, o.pose.y);
  if (switched || vertical_.riding()) {
    mismatch_ = 0;
    return;
  }
  const bool bad = !o.pose_ok || o.inlier_ratio < cfg_.mismatch_ratio;
  if (!bad) {
    mismatch_ = 0;
    mismatch_at_ = p;  // where the plan matched last (the pose may drift once it no longer does)
    return;
  }
  ++mismatch_;
  if (mismatch_ < cfg_.mismatch_frames || (mismatch_ - cfg_.mismatch_frames) % std::max(1, cfg_.probe_every_frames) != 0)
    return;
  std::vector<int> via;
  const std::vector<int> floors = lift_reachable(mismatch_at_, &via);
  if (floors.empty()) return;
  FloorProbe cur;
  cur.floor = floor_;
  cur.name = floor_name();
  const FloorConnection& c0 = building_->connections[size_t(via[size_t(floors.front())])];
  search_disc(c0.polygon, cfg_.connection_margin_m, &cur.search_center, &cur.search_radius_m);
  probe_.push_back(cur);
  for (int f : floors) {
    FloorProbe q;
    q.floor = f;
    q.name = building_->floors[size_t(f)].name;
    q.connection = via[size_t(f)];
    search_disc(building_->connections[size_t(q.connection)].polygon, cfg_.connection_margin_m, &q.search_center,
                &q.search_radius_m);
    probe_.push_back(q);
  }
}

std::optional<FloorSwitch> FloorTracker::probe_result(const std::vector<FloorProbeResult>& results) {
  if (probe_.empty() || results.empty()) return std::nullopt;
  double cur = 0;
  int best = -1;
  double best_ratio = 0;
  for (const auto& r : results) {
    const double ratio = r.ok ? std::clamp(r.inlier_ratio, 0.0, 1.0) : 0.0;
    if (r.floor == floor_) cur = std::max(cur, ratio);
    else if (ratio > best_ratio) best = r.floor, best_ratio = ratio;
  }
  const FloorProbe* q = nullptr;
  for (const auto& p : probe_)
    if (p.floor == best) q = &p;
  std::string others;
  for (const auto& r : results)
    if (r.floor != floor_)
      others += (others.empty() ? "" : ", ") + ("'" + building_->floors[size_t(r.floor)].name + "' ") +
                (r.ok ? fmt("%.0f %%", 100 * r.inlier_ratio) : std::string("no fit"));
  const std::string lift = q ? building_->connections[size_t(q->connection)].name : std::string("?");
  const std::string imu = vertical_.has_gravity() ? "the IMU saw no ride" : "no IMU";
  const std::string here = "the plan of '" + floor_name() + "' no longer matches in lift '" + lift + "' (" +
                           std::to_string(mismatch_) + " frames; " + fmt("%.0f %%", 100 * cur) + " in the lift area, before " +
                           fmt("%.0f %%", 100 * before_inliers_) + "), " + imu;
  if (!q || best_ratio < cfg_.probe_min_ratio || best_ratio < cur + cfg_.probe_margin) {
    text_ = here + "; other floors' plans: " + (others.empty() ? "none" : others) + ": staying on '" + floor_name() + "'";
    probe_.clear();
    return std::nullopt;
  }
  const std::string reason = here + "; the plan of '" + building_->floors[size_t(best)].name + "' matches " +
                             fmt("%.0f %%", 100 * best_ratio) + " (" + others + ")";
  const double e_old = building_->floors[size_t(floor_)].elevation;
  const double before = pose_z_;
  FloorSwitch s = make_switch(best, building_->connections[size_t(q->connection)], reason);
  // The sensor stands on the car's floor, now the new floor's level: its height above the floor is kept,
  // the elevation is the new floor's (no IMU to follow the ride: a jump, said here).
  const double e = building_->floors[size_t(floor_)].elevation;
  if (have_h_) pose_z_ = e + h_;
  text_ += "; z " + fmt("%.2f m", before) + " -> " + fmt("%.2f m", pose_z_) + " ('" + s.to_name + "' at " + fmt("%.2f m", e) +
           " instead of " + fmt("%.2f m", e_old) + ")";
  z_offset_ = 0;
  in_climb_area_ = false;
  have_prev_ = false;
  mismatch_ = 0;
  vertical_.reset();
  probe_.clear();
  return s;
}

std::optional<FloorSwitch> FloorTracker::update_floor(const FloorObservation& o) {
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
  // Once a ride started it continues until the IMU is at rest (the matcher's pose may wander in the car).
  const bool in_lift = (still && near_lift) || (in_lift_ && vertical_.riding());
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
    // How well the plan matched before (frames that matched: a mismatch does not pull it down).
    if (o.pose_ok && o.inlier_ratio >= cfg_.mismatch_ratio)
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
    // (Once known, only z within the gate teaches it: a segmenter off by a wrong ceiling does not.)
    if (!z0_ || std::abs(zf - *z0_) < std::min(cfg_.z_offset_drop_m, cfg_.z_gate_m)) {
      flat_z_.push_back(zf);
      while (int(flat_z_.size()) > cfg_.nominal_z_frames) flat_z_.pop_front();
      if (flat_z_.size() >= 10) z0_ = median(std::vector<double>(flat_z_.begin(), flat_z_.end()));
    }
  }

  // ---- stairs / ramp: the climb since entering the area
  ramp_z_ = 0;
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
  {
    // The segmenter's z did not follow the climb the IMU's tilt measured: floor_z adds it.
    const double tilt_here = enter_elevation_ + tilt_climb_ - e0;
    if (tilt_valid_ && z_climb && std::abs(*z_climb) < 0.5 * std::abs(tilt_here)) ramp_z_ = tilt_here;
  }
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
  if (ramp_z_ != 0) ramp_z_ -= de;
  return s;
}

}  // namespace fploc::localizer
