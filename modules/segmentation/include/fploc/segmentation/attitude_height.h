// The gravity-aligned part of the pose from one scan's planes, robust to ceilings of several heights,
// sloped or cluttered ceilings and atria:
//  - roll/pitch from the ceiling's normal; from the ground's when the ceiling is missing, or when the two
//    disagree (by the IMU's gravity when given, else the floor: floors are level more often than ceilings);
//  - z from the ceiling with the floor-to-ceiling height of the area the sensor is in (configured, else
//    learned online from ceiling + ground: a running median that follows the area), checked against the
//    floor: a ceiling inconsistent with the area's height gives way to the floor plane; with the ceiling
//    alone a step against the last estimate is a new area (z predicted, its height re-learned), never a
//    silent jump; with no trustworthy plane, the last estimate with a sigma that grows every scan.
// Every output says which source it used (attitude_source, z_source) and why in status_text. Transport-free.
#pragma once
#include <Eigen/Core>
#include <deque>
#include <string>

#include "fploc/segmentation/segmentation.h"
#include "fploc/segmentation/segmenter_config.h"

namespace fploc::seg {

struct ImuPrior {
  bool valid = false;                             // use_imu_prior and an IMU sample has arrived
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // gravity up in the sensor frame
};

class AttitudeHeight {
 public:
  explicit AttitudeHeight(const SegmenterConfig& cfg) : cfg_(cfg) {}
  // Fills out.roll/pitch/z, their sigmas and sources from out.ceiling / out.ground (their `found` set).
  // Returns the up vector (sensor frame) the attitude was taken from.
  Eigen::Vector3d update(Segmentation& out, const ImuPrior& imu);
  // A scan whose planes could not be fitted at all (bad or empty input): the predicted estimate.
  void hold(Segmentation& out, const ImuPrior& imu);
  double room_height() const { return room_height_; }  // 0 until known
  // The last measured up vector (ceiling or ground), the prior of the next scan's fits.
  bool has_up() const { return have_prev_; }
  const Eigen::Vector3d& last_up() const { return prev_up_; }
  // Floor-to-ceiling height for wall selection: configured, else learned (0 = unknown).
  double known_room_height() const { return cfg_.ceiling_height_m > 0 ? cfg_.ceiling_height_m : room_height_; }

 private:
  void update_room_height(double h);
  void relearn_room_height(double h);
  void predict_z(Segmentation& out);
  void note(Segmentation& out, const std::string& what) const;

  SegmenterConfig cfg_;
  bool have_prev_ = false;     // an attitude was measured
  bool have_prev_z_ = false;   // a height was measured
  double prev_roll_ = 0, prev_pitch_ = 0, prev_z_ = 0, prev_rp_sigma_ = 0, prev_z_sigma_ = 0;
  double pred_z_sigma_ = 0;
  Eigen::Vector3d prev_up_ = Eigen::Vector3d::UnitZ();    // sigma of the running prediction (grows per predicted scan)
  std::deque<double> heights_;
  double room_height_ = 0.0;
};

}  // namespace fploc::seg
