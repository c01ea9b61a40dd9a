// The NDT peer (issue 12): scan-to-map 3D NDT against the extruded floor plan, the hdl_localization
// approach, on PCL's pcl::NormalDistributionsTransform. Per scan:
//   1. prediction: constant body velocity from the last two estimates, yaw change from the IMU gyro
//      (or the last yaw rate without IMU); roll, pitch and z from the gravity part the segmenter measured
//      (the extruded plan has no floor or ceiling, so NDT cannot observe them);
//   2. voxel-grid downsampling (pcl::VoxelGrid), NDT (6-DoF) from the prediction; no de-skew of its own
//      (hdl_localization has none; the segmenter already de-skews the sweep's rotation with the gyro, and
//      a translation de-skew with the NDT's own velocity made it worse: 13 cm ATE instead of 2 cm);
//   3. the pose is that of the scan's (de-skewed) points, stamped with the scan's start time;
//   4. x, y, yaw from NDT; their covariance from the NDT Hessian at the solution (Laplace approximation:
//      the inverse of the x/y/yaw block of -H, the other three held by the segmenter);
//   5. status: OK when NDT converged, enough points lie on the plan and the covariance is small; POOR
//      otherwise (the prediction is kept when the match is unusable); LOST after many unusable scans.
// No transport here; fploc-ndt (nodes/ndt) feeds it from segments_t and imu_t.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/ndt/plan_cloud.h"

namespace fploc::ndt {

// Defaults follow hdl_localization (hdl_localization_nodelet.cpp + launch file, ndt_omp's defaults).
struct Config {
  PlanCloudOptions map;            // the extruded plan (0..3 m, a point every 0.1 m)
  double resolution_m = 1.0;       // NDT voxel size (hdl: ndt_resolution, 1.0 in its code)
  double step_size_m = 0.1;        // More-Thuente line search maximum step (ndt_omp / PCL default)
  // Convergence: PCL 1.13 stops when the step's squared translation is below this; 1e-4 m^2 is
  // hdl's setTransformationEpsilon(0.01) of ndt_omp (a step shorter than 0.01).
  double epsilon = 1e-4;
  int max_iterations = 35;         // ndt_omp / PCL default
  double outlier_ratio = 0.55;     // PCL's default
  double leaf_m = 0.2;             // input voxel-grid leaf (hdl launch: downsample_resolution 0.2)
  int min_points = 30;             // fewer after downsampling: no match (POOR)
  double inlier_distance_m = 0.5;  // a point this close to the plan (horizontally) is on it (hdl's
                                   // status: max_correspondence_dist 0.5)
  double ok_inlier_ratio = 0.5;    // OK needs at least this share of points on the plan ...
  double poor_sigma_m = 0.3;       // ... and the largest x/y 1-sigma within this
  double min_inlier_ratio = 0.2;   // below: the match is not used (the prediction is kept)
  int lost_after = 10;             // consecutive unusable scans -> LOST
  // The constant-velocity prediction's speed is the platform's at most (hdl_localization predicts with a UKF
  // whose velocity a single jumping match moves only in part): one match 1.3 m off the last pose is not 13 m/s
  // to fly on, scan after scan, while the matches are unusable. <= 0: no limit.
  double max_speed_mps = 2.0;
  double max_yaw_rate_rps = 2.0;
};

enum class Status : int { kOk = 0, kPoor = 1, kLost = 2, kNotInitialised = 3 };
const char* to_string(Status s);

struct Scan {
  double t = 0;                          // scan start time [s]
  std::vector<Eigen::Vector3f> points;   // sensor frame [m]
  double roll = 0, pitch = 0, z = 0;     // gravity part of the sensor pose (segmenter)
};

struct Result {
  Status status = Status::kNotInitialised;
  std::string text;                      // why it is not OK
  double x = 0, y = 0, yaw = 0;          // plan frame, at the scan's start time
  double roll = 0, pitch = 0, z = 0;     // passed through from the scan
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  // x, y, yaw
  bool matched = false;                  // the NDT result was used (else: the prediction)
  bool converged = false;
  int iterations = 0;
  int num_points = 0;                    // after downsampling
  double inlier_ratio = 0;
  double likelihood = 0;                 // PCL's transformation likelihood (score per point)
};

class Localizer {
 public:
  Localizer(const FloorPlan& plan, const Config& cfg = {});
  ~Localizer();
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  void set_pose(double x, double y, double yaw);
  bool initialised() const { return have_pose_; }
  size_t map_points() const;
  // dyaw: the IMU's yaw change since the previous scan (nullopt: the last yaw rate is kept).
  Result process(const Scan& scan, std::optional<double> dyaw = std::nullopt);
  const Config& config() const { return cfg_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Config cfg_;
  bool have_pose_ = false;
  double x_ = 0, y_ = 0, yaw_ = 0, t_ = 0;
  double vx_ = 0, vy_ = 0, w_ = 0;       // body velocity [m/s] and yaw rate [rad/s]
  int bad_ = 0;
};

}  // namespace fploc::ndt
