// AttitudeHeight with a building floor's area ceilings: every ceiling inlier is placed in the plan (the
// localizer's pose of the sensor, extrapolated to the scan) and looked up in the area under it; z is the
// median over the inliers of (that area's floor-to-ceiling height at the point - the point's height above
// the sensor). A ceiling seen across an area boundary thus gives each point its own area's height (no jump
// when the robot passes under the edge); areas without a height in the building learn it online from
// scans whose ceiling lies in one area (ceiling + ground distance, a running median per area).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <utility>

#include "fploc/segmentation/attitude_height.h"
#include "segmenter_constants.h"

namespace fploc::seg {

void AttitudeHeight::set_areas(const AreaCeilingMap& map) {
  areas_ = map;
  areas_.finish();
  area_h_.reset(areas_, cfg_.room_height_window);
  have_areas_ = true;
}

void AttitudeHeight::reset() {
  AttitudeHeight fresh(cfg_);
  if (have_areas_) fresh.set_areas(areas_);
  *this = std::move(fresh);
}

void AttitudeHeight::set_plan_pose(const PlanPose& pose) {
  if (!pose.valid) return;
  if (pose_.valid && pose.utime > pose_.utime) pose_prev_ = pose_;
  else if (pose_.valid && pose.utime < pose_.utime) pose_prev_ = PlanPose{};  // time went back: a new run
  pose_ = pose;
}

bool AttitudeHeight::plan_pose_at(int64_t utime, PlanPose& p) const {
  if (!pose_.valid) return false;
  const double age = 1e-6 * double(utime - pose_.utime);
  if (std::abs(age) > k::kPoseMaxAgeS) return false;
  p = pose_;
  const double dtp = 1e-6 * double(pose_.utime - pose_prev_.utime);
  if (pose_prev_.valid && dtp > 0 && dtp <= k::kPoseMaxExtrapolateS && age > 0) {
    const double f = std::min(age, k::kPoseMaxExtrapolateS) / dtp;
    p.x += f * (pose_.x - pose_prev_.x);
    p.y += f * (pose_.y - pose_prev_.y);
    p.yaw += f * std::remainder(pose_.yaw - pose_prev_.yaw, 2 * M_PI);
  }
  return true;
}

bool AttitudeHeight::census(const Segmentation& out, const Candidates& upper, const Eigen::Vector3d& up_c) {
  PlanPose pp;
  last_utime_ = out.utime;
  if (!plan_pose_at(out.utime, pp)) return false;
  Census& cs = census_;
  cs.p.clear();
  cs.xy.clear();
  cs.area.clear();
  double roll = 0, pitch = 0;
  roll_pitch_from_up(up_c, roll, pitch);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(pp.yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d n = out.ceiling.coeffs.head<3>();
  const double d = out.ceiling.coeffs[3], band = cfg_.inlier_threshold_m;
  const size_t stride = std::max<size_t>(1, (size_t(std::max(0, out.ceiling.inliers)) + k::kAreaMaxPoints - 1) / k::kAreaMaxPoints);
  size_t seen = 0;
  std::map<int, int> count;
  int known = 0;
  for (const Eigen::Vector3f& pf : upper.p) {
    const Eigen::Vector3d p = pf.cast<double>();
    if (std::abs(n.dot(p) + d) > band) continue;
    if (seen++ % stride != 0) continue;
    const Eigen::Vector3d q = R * p;
    const Eigen::Vector2d xy(pp.x + q.x(), pp.y + q.y());
    const int a = areas_.area_at(xy);
    cs.p.push_back(pf);
    cs.xy.push_back(xy);
    cs.area.push_back(a);
    ++count[a];
    if (area_h_.height_at(a, xy) > 0) ++known;
  }
  if (cs.p.empty()) return false;
  const double total = double(cs.p.size());
  cs.dominant = -1;
  int best = 0;
  for (const auto& [a, c] : count)
    if (c > best) {
      best = c;
      cs.dominant = a;
    }
  cs.dominant_fraction = best / total;
  cs.known_fraction = known / total;
  return true;
}

Eigen::Vector3d AttitudeHeight::building_level_up(const Eigen::Vector3d& up_c, double* correction_rad) const {
  // The building's ceiling slope of the area holding most of the ceiling points (the plane fitted lies on
  // one surface); used only when turning the normal by it makes the points fit their heights better.
  *correction_rad = 0;
  const int A = census_.dominant;
  if (A < 0 || !area_h_.known(A) || census_.dominant_fraction < k::kAreaKnownMin) return up_c;
  const Eigen::Vector2d s = areas_.areas[size_t(A)].slope;
  if (s.norm() < k::kMinBuildingSlope) return up_c;
  // The ceiling's upward normal in the plan frame is n_w; the sensor measured it as up_c. Gravity's up in
  // the sensor frame is up_c turned by the rotation taking n_w to e_z, expressed in the sensor frame (which
  // needs the attitude itself: a few fixed-point steps, from the ceiling's).
  const Eigen::Vector3d n_w = Eigen::Vector3d(-s.x(), -s.y(), 1.0).normalized();
  const Eigen::Vector3d a = n_w.cross(Eigen::Vector3d::UnitZ());
  const double theta = std::atan2(a.norm(), n_w.z());
  const Eigen::Vector3d axis_w = a.normalized();
  PlanPose pp;
  if (!plan_pose_at(last_utime_, pp)) return up_c;
  Eigen::Vector3d up = up_c;
  for (int it = 0; it < 4; ++it) {
    double roll = 0, pitch = 0;
    roll_pitch_from_up(up, roll, pitch);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(pp.yaw, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    up = (Eigen::AngleAxisd(theta, R.transpose() * axis_w) * up_c).normalized();
  }
  if (area_spread(up) >= area_spread(up_c)) return up_c;
  *correction_rad = theta;
  return up;
}

double AttitudeHeight::area_spread(const Eigen::Vector3d& up) const {
  std::vector<double> zi;
  zi.reserve(census_.p.size());
  for (size_t i = 0; i < census_.p.size(); ++i) {
    const double H = area_h_.height_at(census_.area[i], census_.xy[i]);
    if (H > 0) zi.push_back(H - up.dot(census_.p[i].cast<double>()));
  }
  if (zi.size() < 3) return 1e9;
  std::nth_element(zi.begin(), zi.begin() + zi.size() / 2, zi.end());
  const double m = zi[zi.size() / 2];
  for (double& v : zi) v = std::abs(v - m);
  std::nth_element(zi.begin(), zi.begin() + zi.size() / 2, zi.end());
  return k::kMadToSigma * zi[zi.size() / 2];
}

void AttitudeHeight::accept_z(Segmentation& out, double z, double sigma, HeightSource src) {
  out.z = z;
  out.z_sigma = sigma;
  out.z_source = src;
  have_prev_z_ = true;
  prev_z_ = z;
  prev_z_sigma_ = sigma;
  pred_z_sigma_ = 0;
}

void AttitudeHeight::area_z(Segmentation& out, const Eigen::Vector3d& up, bool ground_level) {
  const bool c = out.ceiling.found, g = out.ground.found;
  const Census& cs = census_;
  const int A = cs.dominant;
  const std::string& an = areas_.name(A);
  char buf[240];
  const double gate_cg = std::max(cfg_.z_consistency_m, 3.0 * (out.ceiling.d_sigma + out.ground.d_sigma));

  // Learn the area's height (not given by the building) from a level ceiling lying in that one area.
  if (c && g && ground_level && cs.dominant_fraction >= k::kAreaLearnFraction && !area_h_.known(A)) {
    const double ang = std::acos(std::clamp((-out.ceiling.coeffs.head<3>()).dot(out.ground.coeffs.head<3>()), -1.0, 1.0));
    if (ang <= std::max(cfg_.attitude_consistency_deg * k::kDeg, 3.0 * std::hypot(out.ceiling.tilt_sigma, out.ground.tilt_sigma)))
      area_h_.learn(A, out.ceiling.distance() + out.ground.distance());
  }

  // z from the ceiling points with their areas' heights.
  std::vector<double> zi;
  zi.reserve(cs.p.size());
  bool any_learned = false;
  for (size_t i = 0; i < cs.p.size(); ++i) {
    const double H = area_h_.height_at(cs.area[i], cs.xy[i]);
    if (H <= 0) continue;
    any_learned = any_learned || !area_h_.known(cs.area[i]);
    zi.push_back(H - up.dot(cs.p[i].cast<double>()));
  }
  const bool enough = c && double(zi.size()) >= k::kAreaKnownMin * double(cs.p.size()) && !zi.empty();
  if (enough) {
    std::nth_element(zi.begin(), zi.begin() + zi.size() / 2, zi.end());
    const double zc = zi[zi.size() / 2];
    std::vector<double> dev(zi.size());
    for (size_t i = 0; i < zi.size(); ++i) dev[i] = std::abs(zi[i] - zc);
    std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
    const double spread = k::kMadToSigma * dev[dev.size() / 2];
    const double sig = out.ceiling.d_sigma +
                       (any_learned ? out.ground.d_sigma / std::sqrt(double(std::max(1, area_h_.samples(A)))) : 0.0);
    if (spread > std::max(cfg_.z_consistency_m, 3.0 * out.ceiling.rms_m)) {
      std::snprintf(buf, sizeof buf, "ceiling points disagree with their areas' heights (spread %.3f m): ", spread);
      out.note(std::string(buf) + (g ? "z from the ground" : "z predicted"));
    } else if (g && ground_level && std::abs(zc - out.ground.distance()) > gate_cg) {
      std::snprintf(buf, sizeof buf, "ceiling of area '%s' gives z %.3f m, the floor %.3f m: z from the ground", an.c_str(), zc,
                    out.ground.distance());
      out.note(buf);
    } else if (g && ground_level &&
               std::abs(zc - out.ground.distance()) > std::max(k::kAreaFloorGateMinM, 3.0 * (sig + out.ground.d_sigma))) {
      // Inside the consistency gate, but more than 3 of their sigmas (and 1 cm) apart: the ceiling's distance is
      // off by more than its fit says (a far patch seen by the upper rings, its tilt a little off over a lever
      // of metres; a compromise plane across two areas). The level floor's distance is the direct one.
      std::snprintf(buf, sizeof buf, "ceiling of area '%s' gives z %.1f cm off the floor's (> 3 sigmas and 1 cm): z from the ground", an.c_str(),
                    100 * (zc - out.ground.distance()));
      out.note(buf);
    } else if (!g && have_prev_z_ && std::abs(zc - prev_z_) > cfg_.z_jump_m) {
      std::snprintf(buf, sizeof buf, "ceiling of area '%s' steps z by %.3f m without a floor to confirm it: z predicted",
                    an.c_str(), zc - prev_z_);
      out.note(buf);
      predict_z(out);
      if (!area_h_.known(A) && cs.dominant_fraction >= k::kAreaLearnFraction) area_h_.learn(A, prev_z_ + out.ceiling.distance());
      return;
    } else {
      std::snprintf(buf, sizeof buf, "z: ceiling, area '%s' (%s height)", an.c_str(),
                    area_h_.known(A) ? "building" : "learned");
      out.note(buf);
      accept_z(out, zc, sig, HeightSource::kCeiling);
      return;
    }
  } else if (c) {
    std::snprintf(buf, sizeof buf, "ceiling over area '%s' of unknown height (%d samples): ", an.c_str(), area_h_.samples(A));
    out.note(std::string(buf) + (g ? "z from the ground" : "z predicted, height learned from it"));
    if (!g) {
      predict_z(out);
      if (have_prev_z_ && !area_h_.known(A) && cs.dominant_fraction >= k::kAreaLearnFraction)
        area_h_.learn(A, prev_z_ + out.ceiling.distance());
      return;
    }
  }
  if (g) {
    accept_z(out, out.ground.height(), out.ground.d_sigma, HeightSource::kGround);
  } else {
    predict_z(out);
  }
}

}  // namespace fploc::seg
