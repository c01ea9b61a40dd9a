// The gravity-aligned part of the pose from one scan's planes, robust to ceilings of several heights,
// sloped or cluttered ceilings and atria:
//  - roll/pitch from the ceiling's normal; from the ground's when the ceiling is missing, or when the two
//    disagree (by the IMU's gravity when given, else the floor: floors are level more often than ceilings);
//  - z from the ceiling with the floor-to-ceiling height of the area the sensor is in (configured, else
//    learned online from ceiling + ground: a running median that follows the area), checked against the
//    floor: a ceiling inconsistent with the area's height gives way to the floor plane; with the ceiling
//    alone a step against the last estimate is a new area (z predicted, its height re-learned), never a
//    silent jump; with no trustworthy plane, the last estimate with a sigma that grows every scan.
// With a building floor's area ceilings (set_areas) and the sensor's plan pose (set_plan_pose, the localizer's
// feedback), z comes from every ceiling inlier with the height of the area under that point (the building's,
// else learned online per area); see attitude_height_areas.cpp.
// Every output says which source it used (attitude_source, z_source) and why in status_text. Transport-free.
#pragma once
#include <Eigen/Core>
#include <deque>
#include <string>

#include "fploc/segmentation/area_ceilings.h"
#include "fploc/segmentation/candidates.h"
#include "fploc/segmentation/segmentation.h"
#include "fploc/segmentation/segmenter_config.h"

namespace fploc::seg {

struct ImuPrior {
  bool valid = false;                             // use_imu_prior and an IMU sample has arrived
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // gravity up in the sensor frame
  // The samples of this scan measured gravity alone (|mean| near g, small spread: no jolt, no
  // acceleration); only then does the IMU arbitrate between a ceiling and a floor that disagree.
  bool trusted = false;
};

class AttitudeHeight {
 public:
  explicit AttitudeHeight(const SegmenterConfig& cfg) : cfg_(cfg) {}
  // Fills out.roll/pitch/z, their sigmas and sources from out.ceiling / out.ground (their `found` set).
  // Returns the up vector (sensor frame) the attitude was taken from.
  // `upper`: the scan's ceiling candidates (sensor frame), used with the area ceilings only.
  Eigen::Vector3d update(Segmentation& out, const ImuPrior& imu, const Candidates* upper = nullptr);
  // A building floor's ceilings: z from the area under each ceiling point once a plan pose is known.
  void set_areas(const AreaCeilingMap& map);
  // The sensor's pose in the plan frame (the localizer's latest); the next scans extrapolate from the last two.
  void set_plan_pose(const PlanPose& pose);
  // Everything learned from the scans and poses as after construction (then set_areas with the areas given,
  // if any: their learned heights start anew); the configuration and the areas kept (Segmenter::reset).
  void reset();
  bool has_areas() const { return have_areas_; }
  const AreaHeights& area_heights() const { return area_h_; }
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
  // The building path of z (attitude_height_areas.cpp); false when it cannot say (no fresh pose): the
  // single-height path runs instead.
  // The ceiling inliers' areas (under the plan pose at the scan's time); false without a fresh pose.
  bool census(const Segmentation& out, const Candidates& upper, const Eigen::Vector3d& up_c);
  void area_z(Segmentation& out, const Eigen::Vector3d& up, bool ground_level);
  // Robust spread of the per-point z (area height - height above the sensor along `up`) over the census.
  double area_spread(const Eigen::Vector3d& up) const;
  // Gravity's up from the ceiling's measured up when the building says the ceiling over these points is
  // sloped (a ceiling following a ramp, a roof): the measured normal turned by the known slope.
  Eigen::Vector3d building_level_up(const Eigen::Vector3d& up_c, double* correction_rad) const;
  int64_t last_utime_ = 0;
  bool plan_pose_at(int64_t utime, PlanPose& p) const;
  void accept_z(Segmentation& out, double z, double sigma, HeightSource src);
  struct Census {
    std::vector<Eigen::Vector3f> p;      // ceiling inliers (sensor frame, subsampled)
    std::vector<Eigen::Vector2d> xy;     // their plan x/y
    std::vector<int> area;               // their area (-1 = the floor's default region)
    int dominant = -1;                   // the area holding most of them
    double dominant_fraction = 0, known_fraction = 0;
  };
  Census census_;

  SegmenterConfig cfg_;
  bool have_prev_ = false;     // an attitude was measured
  bool have_prev_z_ = false;   // a height was measured
  double prev_roll_ = 0, prev_pitch_ = 0, prev_z_ = 0, prev_rp_sigma_ = 0, prev_z_sigma_ = 0;
  double pred_z_sigma_ = 0;
  Eigen::Vector3d prev_up_ = Eigen::Vector3d::UnitZ();    // sigma of the running prediction (grows per predicted scan)
  std::deque<double> heights_;
  double room_height_ = 0.0;
  // Building areas.
  bool have_areas_ = false;
  AreaCeilingMap areas_;
  AreaHeights area_h_;
  PlanPose pose_, pose_prev_;
  // The sensor's usual up vector on level floors (ramp detection with the IMU or a building).
  bool have_level_up_ = false;
  Eigen::Vector3d level_up_ = Eigen::Vector3d::UnitZ();
};

}  // namespace fploc::seg
