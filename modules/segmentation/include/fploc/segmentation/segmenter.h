// Ceiling/ground segmentation (paper section IV-A): the gravity-aligned part of the pose (roll, pitch,
// height) from the ceiling plane, and the wall points (vertical structure between floor and ceiling).
// Transport-free; nodes/segmenter wraps it. No PCL here (the RANSAC plane fit keeps PCL in its .cpp).
//
// One scan goes through: point preparation (point_prep.cpp: XYZ, range gate, gyro de-skew by GyroDeskew,
// the upper/lower half-ring candidates) -> the plane fit strategy (PlaneFit: RingPlaneFit, the paper's, or
// RansacPlaneFit) for the ceiling and the ground -> plane quality and acceptance (plane_quality.cpp,
// segmenter.cpp) -> with a gyro, the ground at a kink (ground_kink.cpp; its cells in kink_cells.cpp) ->
// attitude and height (AttitudeHeight) -> wall selection (wall_select.cpp).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "fploc/core/scan.h"
#include "fploc/core/xyz.h"
#include "fploc/segmentation/attitude_height.h"
#include "fploc/segmentation/beam_scaling.h"
#include "fploc/segmentation/candidates.h"
#include "fploc/segmentation/gravity_fusion.h"
#include "fploc/segmentation/gyro_deskew.h"
#include "fploc/segmentation/plane_fit.h"
#include "fploc/segmentation/segmentation.h"
#include "fploc/segmentation/segmenter_config.h"

namespace fploc::seg {

class Segmenter {
 public:
  Segmenter(SegmenterConfig cfg, std::unique_ptr<PlaneFit> fit);
  virtual ~Segmenter();
  const char* name() const { return fit_->name(); }

  // Segments one scan. Never throws on bad data: the status says what was wrong.
  const Segmentation& process(const Scan& scan);
  // Starts again as a new segmenter (a time jump: a log or a simulated sequence played again from its start).
  // Everything carried from scan to scan -- the planes followed, the IMU samples and gyro bias, the gravity
  // fusion, attitude and height, the surface followed at a kink, the diagnostics counters, the last output --
  // as after construction; the configuration, set_keep_labels, the areas given (set_areas; their learned heights
  // start anew) and the scratch arrays with their capacity (the look-up table of the last beam pattern, the
  // candidates, the wall points, the kink split's cells) kept. The next scans' outputs are a new segmenter's, bit
  // for bit (segmentation_gravity_fusion_test: ResetGivesANewSegmentersOutputs), without its first scans'
  // allocations and page faults. A member added below that is carried from scan to scan must be reset there.
  void reset();
  const Segmentation& last() const { return out_; }

  // IMU accelerometer sample (specific force, m/s^2) in the sensor frame; averaged until the next scan.
  void add_accel(const Eigen::Vector3d& accel);
  // IMU gyro sample (rad/s, sensor frame) measured at utime [us, the scan's clock]. Samples covering a
  // sweep de-skew its rotation (config deskew_gyro); without them the scan is used as measured.
  void add_gyro(const Eigen::Vector3d& rate, int64_t utime) {
    deskew_.add(rate, utime);
    if (cfg_.imu_attitude) fusion_.add_gyro(rate, utime);  // roll/pitch against gravity (segmenter_imu.cpp)
  }
  void set_keep_labels(bool on) { keep_labels_ = on; }
  // A building floor's area ceilings and the sensor's plan pose (the localizer's feedback): z from the
  // height of the area under each ceiling point (AttitudeHeight, attitude_height_areas.cpp).
  void set_areas(const AreaCeilingMap& map) { height_.set_areas(map); }
  void set_plan_pose(const PlanPose& pose) { height_.set_plan_pose(pose); }
  const AttitudeHeight& height_estimator() const { return height_; }
  const GravityFusion& gravity_fusion() const { return fusion_; }
  const SegmenterConfig& config() const { return cfg_; }
  double room_height() const { return height_.room_height(); }  // 0 until known
  // The sensor-dependent numbers in use (from the last scan's beam pattern, beam_scaling.h).
  const BeamScaling& beam_scaling() const { return scale_; }
  const Eigen::Vector3d& gyro_bias() const { return deskew_.bias(); }  // rad/s, perpendicular-to-gravity part
  // Scans whose ground-at-a-kink split was skipped, one surface followed steadily (SegmenterConfig::kink_recheck_scans).
  int64_t kink_splits_skipped() const { return kink_skipped_; }
  // Rechecks of a steadily followed surface that the thinned returns settled (SegmenterConfig::kink_recheck_stride).
  int64_t kink_rechecks_thinned() const { return kink_thinned_; }
  // Plane fits that refined last frame's plane without the start search (SegmenterConfig::start_recheck_scans).
  int64_t steady_plane_fits() const { return fit_->steady_fits(); }
  // Last scan's points per pixel (row-major like the scan, de-skewed when last().deskewed; NaN where there
  // is no return inside [min_range_m, max_range_m]). Diagnostics: built on each call.
  const std::vector<Eigen::Vector3f>& points() const;

 private:
  bool prepare(const Scan& scan);
  static double mid_sweep_offset(const Scan& scan);
  void quality(const Candidates& c, Plane& pl) const;
  void fit_ceiling(const Eigen::Vector3d& init_up, const Eigen::Vector3d& gate_up);
  void fit_ground(const Eigen::Vector3d& up, bool from_previous = true);  // from_previous: start from last scan's ground
  // Two surfaces under the lower rings (a ramp's foot or head): the ground the attitude follows and the height
  // above the one under the robot (ground_kink.cpp). t: the planes' time (mid-sweep).
  // scan: its column times (the sweep's translation, which the gyro de-skew leaves in the points).
  void split_ground_at_kink(int64_t t, const Scan& scan);
  // The split itself on every stride-th return near the ring fit (up: the ring fit's normal, prev: the followed
  // surface carried to t); true when it found the one surface again and re-armed the skipping (the planes
  // unchanged).
  bool split_ground(int64_t t, const Scan& scan, const Eigen::Vector3d& up, Eigen::Vector3d prev, bool ground_attitude,
                    int stride);
  // No ground found: the ground fitted around gravity as the gyro carries it to t, the planes' time (segmenter.cpp).
  void refit_ground_around_gravity(int64_t t);
  void select_walls(const Scan& scan, const Eigen::Vector3d& up);
  // The IMU's part of roll/pitch (segmenter_imu.cpp): gravity vs the planes' up, then the attitude moved from
  // mid-sweep to the scan's time with the gyro.
  void fuse_imu(const Scan& scan, const Eigen::Vector3d& plane_up);
  void attitude_to_scan_time(const Scan& scan);

  SegmenterConfig cfg_;
  std::unique_ptr<PlaneFit> fit_;
  GyroDeskew deskew_;
  GravityFusion fusion_;
  AttitudeHeight height_;
  Segmentation out_;
  XyzLut lut_;
  BeamScaling scale_;
  BeamIntrinsics lut_beams_;
  int lut_width_ = 0;
  mutable std::vector<Eigen::Vector3f> points_;  // points() (diagnostics)
  std::vector<float> col_dt_;  // per staggered column: column time - scan utime [s]
  std::vector<int> ring_order_;      // rings sorted by altitude, top first
  std::vector<int> col_mid_;
  std::vector<uint8_t> col_ok_;
  std::vector<int32_t> col_okm_;            // col_ok_ as lane masks (-1 / 0)
  std::vector<float> lut_soa_[6];           // lut_ as float arrays: direction x/y/z, offset x/y/z
  std::vector<std::array<float, 2>> row_z_;  // per row: z direction and offset when one value each, else NaN
  bool col_identity_ = false;               // this scan's look-up columns are its own (lut_soa_ per pixel)
  bool raw_z_from_range_ = false;           // candidate ranges give the mm back exactly (wallk::kExactRangeMm)
  std::vector<int8_t> row_set_;   // per scan row: 0 upper_, 1 lower_, 2 middle_ (with row_ring_: its ring there)
  std::vector<int> row_ring_;
  struct WallPiece {  // wall selection: a contiguous run of one row's candidates (wall_select.cpp)
    const Candidates* cs;
    int32_t a, b, off;
    int16_t u;
  };
  std::vector<WallPiece> pieces_;
  std::vector<uint8_t> masks_;  // wall selection: lane mask of each group of four candidates
  Candidates upper_, lower_, middle_;  // middle_: an odd beam count's middle ring (wall points only)
  bool keep_labels_ = false;

  // Plane tracking (priors for the next scan's fits and wall bounds).
  bool have_prev_ceiling_ = false, have_prev_ground_ = false;
  Eigen::Vector4d prev_ceiling_, prev_ground_;
  // The ground surface followed across a kink (ground_kink.cpp): its normal at its mid-sweep time.
  Eigen::Vector3d follow_up_ = Eigen::Vector3d::UnitZ();
  int64_t follow_t_ = 0;
  // ... its distance from the sensor then, and the rate of that distance (the sensor's speed off the surface,
  // low-passed; valid while the same surface is followed scan after scan).
  struct FollowRate {
    double d = 0, rate = 0, var = 0, gain = 1;  // (var: of the raw rates)
    int64_t d_t = 0;
    bool ok = false;
    // The surface's distance d_now at t (same_surface: the one of the last update).
    void update(int64_t t, double d_now, bool same_surface);
    // The rate stands out of its own noise (2 sigmas of the weighted mean): the sweep's translation is corrected.
    bool stands_out() const;
  };
  FollowRate follow_;
  // Scans the ground-at-a-kink split may still be skipped for while one surface is followed steadily
  // (ground_kink.cpp, SegmenterConfig::kink_recheck_scans); and how many it was skipped for (diagnostics).
  int kink_quiet_left_ = 0;
  double kink_skew_per_rate_ = 0;   // the last split's sweep tilt of the followed surface per m/s of the rate [rad s/m]
  double kink_d_offset_ = 0;         // the last split's followed surface's distance - the ring fit's [m]
  int64_t kink_skipped_ = 0;
  bool kink_armed_ = false;     // the last split re-armed the skipping (the next one that runs while quiet: a recheck)
  int64_t kink_thinned_ = 0;    // rechecks kept from the thinned returns (kink_recheck_stride)
  // ground_kink.cpp's scratch, kept from scan to scan: the lower candidates near the ring fit's plane (their
  // indices and sectors), and the sectors' points grouped (sector by sector, relative to the plane's reference
  // point), the followed surface's.
  std::vector<int32_t> kink_index_;
  std::vector<int16_t> kink_sector_;
  std::vector<float> kink_x_, kink_y_, kink_z_, near_x_, near_y_, near_z_;
  std::vector<float> sweep_q_;  // the sweep correction's returns as measured and moved back (ground_kink.cpp)
  Eigen::Vector3d accel_sum_ = Eigen::Vector3d::Zero();
  double accel_sq_ = 0;  // sum of |a|^2 (the spread: is the IMU measuring gravity alone?)
  int accel_n_ = 0;
  bool imu_trusted_ = false;
  Eigen::Vector3d imu_up_ = Eigen::Vector3d::UnitZ();
  bool have_imu_ = false;
  bool have_prev_mid_z_ = false;  // the last measured z at its mid-sweep time (z moved to utime)
  int64_t prev_mid_t_ = 0;
  double prev_mid_z_ = 0;
  bool accel_this_scan_ = false;  // samples arrived since the last scan (accel_mean_ is theirs)
  Eigen::Vector3d accel_mean_ = Eigen::Vector3d::Zero();
};

// The paper's segmenter: max-range seeds on the top K_r rings, linear regression, IRLS (Tukey).
class RingSegmenter : public Segmenter {
 public:
  explicit RingSegmenter(SegmenterConfig cfg) : Segmenter(cfg, std::make_unique<RingPlaneFit>(cfg)) {}
};

}  // namespace fploc::seg
