#include "fploc/segmentation/attitude_height.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "segmenter_constants.h"

namespace fploc::seg {

void AttitudeHeight::update_room_height(double h) {
  heights_.push_back(h);
  while (int(heights_.size()) > std::max(1, cfg_.room_height_window)) heights_.pop_front();
  std::vector<double> v(heights_.begin(), heights_.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  room_height_ = v[v.size() / 2];
}

void AttitudeHeight::hold(Segmentation& out, const ImuPrior& imu) const {
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
  if (have_prev_) {
    out.z = prev_z_;
    out.z_sigma = std::max(prev_z_sigma_ * k::kHoldGrowth, k::kMinHeldZSigmaM);
  } else {
    out.z = 0;
    out.z_sigma = k::kUnknownZSigmaM;
  }
}

void AttitudeHeight::update(Segmentation& out, const Eigen::Vector3d& up, const ImuPrior& imu) {
  // Height: sensor height above the floor = room height - distance to the ceiling.
  if (out.ceiling.found && out.ground.found && cfg_.ceiling_height_m <= 0)
    update_room_height(out.ceiling.distance() + out.ground.distance());
  const double H = known_room_height();
  if (out.ceiling.found) {
    roll_pitch_from_up(up, out.roll, out.pitch);
    out.roll_pitch_sigma = out.ceiling.tilt_sigma;
    out.attitude_source = AttitudeSource::kCeiling;
    if (H > 0) {
      out.z = H - out.ceiling.distance();
      out.z_sigma = out.ceiling.d_sigma +
                    (cfg_.ceiling_height_m > 0 ? 0.0 : out.ground.d_sigma / std::sqrt(double(heights_.size())));
    } else if (out.ground.found) {
      out.z = out.ground.distance();
      out.z_sigma = out.ground.d_sigma;
    } else {
      out.z = have_prev_ ? prev_z_ : 0.0;
      out.z_sigma = have_prev_ ? std::max(prev_z_sigma_ * k::kHoldGrowth, k::kMinHeldZSigmaM) : k::kUnknownZSigmaM;
    }
    have_prev_ = true;
    prev_roll_ = out.roll;
    prev_pitch_ = out.pitch;
    prev_z_ = out.z;
    prev_rp_sigma_ = out.roll_pitch_sigma;
    prev_z_sigma_ = out.z_sigma;
  } else {
    hold(out, imu);
    if (out.ground.found) {
      out.z = out.ground.distance();
      out.z_sigma = out.ground.d_sigma;
    }
  }
}

}  // namespace fploc::seg
