#include "fploc/segmentation/attitude_height.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "segmenter_constants.h"

namespace fploc::seg {

const char* to_string(AttitudeSource s) {
  switch (s) {
    case AttitudeSource::kCeiling: return "ceiling";
    case AttitudeSource::kPrevious: return "previous";
    case AttitudeSource::kImu: return "imu";
    case AttitudeSource::kNone: return "none";
    case AttitudeSource::kGround: return "ground";
    case AttitudeSource::kSlope: return "planes+slope";
    case AttitudeSource::kGyro: return "gyro";
  }
  return "?";
}

const char* to_string(HeightSource s) {
  switch (s) {
    case HeightSource::kCeiling: return "ceiling";
    case HeightSource::kGround: return "ground";
    case HeightSource::kPredicted: return "predicted";
    case HeightSource::kNone: return "none";
  }
  return "?";
}

void AttitudeHeight::update_room_height(double h) {
  heights_.push_back(h);
  while (int(heights_.size()) > std::max(1, cfg_.room_height_window)) heights_.pop_front();
  std::vector<double> v(heights_.begin(), heights_.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  room_height_ = v[v.size() / 2];
}

void AttitudeHeight::relearn_room_height(double h) {
  heights_.clear();
  update_room_height(h);
}

void AttitudeHeight::predict_z(Segmentation& out) {
  // The last estimate (the platform's height changes slowly), its sigma doubling per predicted scan.
  if (have_prev_z_) {
    pred_z_sigma_ = std::max(pred_z_sigma_ * k::kHoldGrowth, std::max(prev_z_sigma_, k::kMinHeldZSigmaM));
    out.z = prev_z_;
    out.z_sigma = pred_z_sigma_;
    out.z_source = HeightSource::kPredicted;
  } else {
    out.z = 0;
    out.z_sigma = k::kUnknownZSigmaM;
    out.z_source = HeightSource::kNone;
  }
}

void AttitudeHeight::hold(Segmentation& out, const ImuPrior& imu) {
  if (imu.valid) {
    roll_pitch_from_up(imu.up, out.roll, out.pitch);
    out.roll_pitch_sigma = k::kImuTiltSigmaRad;
    out.attitude_source = AttitudeSource::kImu;
  } else if (have_prev_) {
    out.roll = prev_roll_;
    out.pitch = prev_pitch_;
    out.roll_pitch_sigma = std::max(prev_rp_sigma_ * k::kHoldGrowth, k::kMinHeldTiltSigmaRad);
    out.attitude_source = AttitudeSource::kPrevious;
  } else {
    out.roll = out.pitch = 0;
    out.roll_pitch_sigma = M_PI;
    out.attitude_source = AttitudeSource::kNone;
  }
  predict_z(out);
}

Eigen::Vector3d AttitudeHeight::update(Segmentation& out, const ImuPrior& imu, const Candidates* upper) {
  const bool c = out.ceiling.found, g = out.ground.found;
  Eigen::Vector3d up_c = -out.ceiling.coeffs.head<3>();  // normals point into the room
  const Eigen::Vector3d up_g = out.ground.coeffs.head<3>();

  // The building's view of the ceiling points (their areas), when the floor's areas and a plan pose are known.
  const bool areas_on = have_areas_ && upper != nullptr && c && census(out, *upper, up_c);
  if (areas_on && cfg_.building_attitude) {
    // A ceiling the building says is sloped (over a ramp, under a roof) gives gravity's up once turned by
    // its slope.
    double corr = 0;
    const Eigen::Vector3d level = building_level_up(up_c, &corr);
    if (corr > 0) {
      char buf[120];
      std::snprintf(buf, sizeof buf, "ceiling sloped %.2f deg per the building: its normal turned by that", corr / k::kDeg);
      out.note(buf);
      up_c = level;
    }
  }

  // ---- roll / pitch ----
  bool use_ceiling = c, use_ground = !c && g;
  // Ceiling and floor parallel: only then is ceiling + ground distance a floor-to-ceiling height (a sloped
  // ceiling's distance is along its own normal and holds nowhere but at its foot).
  bool parallel = c && g;
  if (c && g) {
    const double ang = std::acos(std::clamp(up_c.dot(up_g), -1.0, 1.0));
    const double gate = std::max(cfg_.attitude_consistency_deg * k::kDeg,
                                 3.0 * std::hypot(out.ceiling.tilt_sigma, out.ground.tilt_sigma));
    if (ang > gate) {
      parallel = false;
      // One of them is not level (a sloped ceiling under a roof or stairs, a compromise over two ceiling
      // surfaces, a ramp under the sensor): the IMU decides when given, else the floor (floors are level
      // far more often than the ceilings above them).
      // A robot on a ramp sees the same pair of planes as a level robot under a sloped ceiling; what tells
      // them apart: the IMU's gravity when this scan's samples measured gravity alone (no jolt), the
      // building (the ceiling over these points is flat, or sloped), and otherwise the IMU even when shaken,
      // else the floor.
      bool ground_better = true;
      const char* by = "floors are level more often than ceilings";
      char by_buf[120];
      if (imu.valid && imu.trusted) {
        ground_better = up_g.dot(imu.up) > up_c.dot(imu.up);
        by = "IMU gravity";
      } else if (areas_on && cfg_.building_attitude && census_.known_fraction > k::kAreaKnownMin) {
        // The building's ceiling heights: under the right attitude the ceiling points lie at their areas'
        // heights (one z for all); under the wrong one they trend across the scan (a ramp seen as a
        // sloped ceiling, or a compromise plane over two ceilings taken as level).
        const double sc = area_spread(up_c), sg = area_spread(up_g);
        ground_better = sg <= sc;
        std::snprintf(by_buf, sizeof by_buf, "the building's ceiling heights fit it better: spread %.1f cm vs %.1f cm",
                      100 * std::min(sc, sg), 100 * std::max(sc, sg));
        by = by_buf;
      } else if (imu.valid) {
        ground_better = up_g.dot(imu.up) > up_c.dot(imu.up);
        by = "IMU gravity (shaken)";
      }
      if (ground_better) {
        use_ceiling = false;
        use_ground = true;
      }
      char buf[240];
      std::snprintf(buf, sizeof buf, "ceiling and ground normals %.2f deg apart: attitude from the %s (%s)", ang / k::kDeg,
                    ground_better ? "ground" : "ceiling", by);
      out.note(buf);
    }
  }
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  if (use_ceiling || use_ground) {
    const Plane& pl = use_ceiling ? out.ceiling : out.ground;
    up = use_ceiling ? up_c : up_g;
    roll_pitch_from_up(up, out.roll, out.pitch);
    out.roll_pitch_sigma = pl.tilt_sigma;
    out.attitude_source = use_ceiling ? AttitudeSource::kCeiling : AttitudeSource::kGround;
    have_prev_ = true;
    prev_up_ = up;
    prev_roll_ = out.roll;
    prev_pitch_ = out.pitch;
    prev_rp_sigma_ = out.roll_pitch_sigma;
  } else {
    hold(out, imu);  // sets a predicted z too; overwritten below when a plane gives one
    up = imu.valid ? imu.up : up_from_roll_pitch(out.roll, out.pitch);
  }

  // ---- z ----
  const bool known = cfg_.ceiling_height_m > 0;
  // The floor is level under the attitude taken (not a ramp under the robot): only then is its distance the
  // height above the area's floor. Without an IMU or a building the attitude is the floor's whenever the two
  // disagree, so this only differs from "the ground was found" when one of them said "ramp".
  const double ang_g = g ? std::acos(std::clamp(up_g.dot(up), -1.0, 1.0)) : M_PI;
  bool ground_level = g && ang_g <= std::max(cfg_.attitude_consistency_deg * k::kDeg,
                                             3.0 * std::hypot(out.ground.tilt_sigma, out.roll_pitch_sigma));
  // With a witness of gravity other than the two planes (the IMU, the building): the robot tilted away from
  // its usual attitude on level floors (the running mean of the up vector there) is on a ramp, at its ends or
  // on a threshold; the floor it sees is then not the level of the area's floor (a mix of ramp and landing).
  if (imu.valid || have_areas_) {
    const double off = std::acos(std::clamp(up.dot(level_up_), -1.0, 1.0));
    if (have_level_up_ && off > k::kOnSlopeDeg * k::kDeg && (use_ceiling || imu.trusted)) {
      if (ground_level) out.note("robot tilted on a ramp or threshold: the floor is not the area's level");
      ground_level = false;
    } else if (ground_level && off < k::kOnSlopeDeg * k::kDeg) {
      level_up_ = have_level_up_ ? (level_up_ + k::kLevelUpGain * (up - level_up_)).normalized() : up;
      have_level_up_ = true;
    }
  }
  if (areas_on) {
    if (parallel && ground_level && !known) update_room_height(out.ceiling.distance() + out.ground.distance());  // wall selection
    area_z(out, up, ground_level);
    return up;
  }
  if (g && !ground_level && use_ceiling && known_room_height() > 0) {
    // A ramp (or a tilted floor patch) under the robot, the ceiling level: z from the ceiling, the floor's
    // distance is not the height above the area's floor.
    out.note("floor tilted under the robot (a ramp): z from the ceiling");
  }
  // A ceiling not parallel to the floor (a sloped roof, a compromise over two surfaces) gave no attitude and
  // gives no z (use_ceiling is off), and no room height either: learning its distances would shift the running
  // median by a few cm, under the consistency gate, and the next level ceiling would put z off by that much.
  if (parallel && ground_level && !known) {
    const double h = out.ceiling.distance() + out.ground.distance();
    const double tol = 3.0 * (out.ceiling.d_sigma + out.ground.d_sigma);
    if (room_height_ > 0 && std::abs(h - room_height_) > std::max(cfg_.z_consistency_m, tol)) {
      // The ceiling over the sensor is not the area's (yet): z from the floor; the running median follows
      // when the new height persists (another area).
      char buf[160];
      std::snprintf(buf, sizeof buf, "ceiling %.3f m above the floor vs the area's %.3f m: z from the ground", h,
                    room_height_);
      out.note(buf);
      use_ceiling = false;
    } else if (room_height_ > 0 && std::abs(h - room_height_) > tol) {
      // The same area, but the ceiling's z (the area's height - its distance) and the floor's differ by
      // h - height: more than 3 of their sigmas, so the ceiling's distance is off by more than its fit says
      // (a far patch, its tilt a little off: a lever of metres). The floor's distance is the direct one.
      char buf[160];
      std::snprintf(buf, sizeof buf, "ceiling's z %.1f cm off the floor's (> 3 sigmas, %.1f cm): z from the ground",
                    100 * (room_height_ - h), 100 * tol);
      out.note(buf);
      use_ceiling = false;
    }
    update_room_height(h);
  }
  const double H = known_room_height();
  bool measured = false;
  if (use_ceiling && H > 0) {
    const double z = H - out.ceiling.distance();
    const double sig = out.ceiling.d_sigma + (known ? 0.0 : out.ground.d_sigma / std::sqrt(double(std::max<size_t>(1, heights_.size()))));
    if (!g && have_prev_z_ && std::abs(z - prev_z_) > cfg_.z_jump_m) {
      // Ceiling alone and a step: another area (or a beam, a lamp). Not a jump of the platform: predict,
      // and take this ceiling's height as the area's from now on (learned online).
      char buf[160];
      std::snprintf(buf, sizeof buf, "ceiling step of %.3f m without a floor to confirm it: z predicted, area height re-learned",
                    z - prev_z_);
      out.note(buf);
      predict_z(out);
      if (!known) relearn_room_height(prev_z_ + out.ceiling.distance());
    } else {
      out.z = z;
      out.z_sigma = sig;
      out.z_source = HeightSource::kCeiling;
      measured = true;
    }
  } else if (g && (ground_level || !have_prev_z_)) {
    out.z = out.ground.height();  // the surface under the robot (at a ramp's foot or head, ground_kink.cpp)
    out.z_sigma = out.ground.d_sigma;
    out.z_source = HeightSource::kGround;
    measured = true;
  } else if (use_ceiling || use_ground) {
    predict_z(out);
  }
  if (measured) {
    have_prev_z_ = true;
    prev_z_ = out.z;
    prev_z_sigma_ = out.z_sigma;
    pred_z_sigma_ = 0;
  }
  return up;
}

}  // namespace fploc::seg
