// The gravity-aligned part of the pose from one scan's planes: roll/pitch from the ceiling's normal, the
// height from the ceiling (and the floor-to-ceiling height learned from ceiling + ground), with fallbacks
// (IMU gravity, the previous estimate with a grown sigma) when the planes are not there. Transport-free.
#pragma once
#include <Eigen/Core>
#include <deque>

#include "fploc/segmentation/segmentation.h"
#include "fploc/segmentation/segmenter_config.h"

namespace fploc::seg {

struct ImuPrior {
  bool valid = false;                         // use_imu_prior and an IMU sample has arrived
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // gravity up in the sensor frame
};

class AttitudeHeight {
 public:
  explicit AttitudeHeight(const SegmenterConfig& cfg) : cfg_(cfg) {}
  // Fills out.roll/pitch/z, their sigmas and sources from out.ceiling / out.ground (their `found` set);
  // `up` is the ceiling's up vector when the ceiling was found.
  void update(Segmentation& out, const Eigen::Vector3d& up, const ImuPrior& imu);
  // A scan whose planes could not be fitted at all (bad or empty input): the held estimate.
  void hold(Segmentation& out, const ImuPrior& imu) const;
  double room_height() const { return room_height_; }  // 0 until known
  // Floor-to-ceiling height for wall selection: configured, else learned (0 = unknown).
  double known_room_height() const { return cfg_.ceiling_height_m > 0 ? cfg_.ceiling_height_m : room_height_; }

 private:
  void update_room_height(double h);

  SegmenterConfig cfg_;
  bool have_prev_ = false;
  double prev_roll_ = 0, prev_pitch_ = 0, prev_z_ = 0, prev_rp_sigma_ = 0, prev_z_sigma_ = 0;
  std::deque<double> heights_;
  double room_height_ = 0.0;
};

}  // namespace fploc::seg
