// Ceiling/ground segmentation (paper section IV-A): the gravity-aligned part of the pose (roll, pitch,
// height) from the ceiling plane, and the wall points (vertical structure between floor and ceiling).
// Transport-free; nodes/segmenter wraps it. No PCL here (the RANSAC variant keeps PCL in its .cpp).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fploc/core/scan.h"
#include "fploc/core/xyz.h"

namespace fploc::seg {

struct SegmenterConfig {
  int seed_rings = 4;              // K_r: top (bottom) rings giving the seed points
  int seed_sectors = 64;           // azimuth sectors per seed ring (one max-range candidate each)
  double seed_fraction = 0.25;     // keep this fraction of the sector maxima (largest ranges) per ring
  int seed_triplets = 40;          // planes through seed triplets also tried as the IRLS start
  double max_tilt_deg = 10.0;      // reject planes tilted more than this from the gravity prior
  double wall_margin_m = 0.10;     // points closer than this to ceiling/floor are not wall points
  double ceiling_height_m = 0.0;   // known floor-to-ceiling height; 0 = estimated (ceiling + ground fits)
  bool use_imu_prior = false;      // IMU gravity as initial direction, tilt gate and fallback
  bool deskew_gyro = true;         // rotate returns to mid-sweep with the gyro rate (when gyro samples arrive)
  double min_range_m = 0.4;        // ignore returns closer than this (platform, tripod)
  double max_range_m = 120.0;
  int min_plane_inliers = 200;     // fewer inliers -> plane not found
  double min_inlier_fraction = 0.02;  // of the upper (lower) half-ring returns (a corridor ceiling: ~3 %)
  double max_beyond_ratio = 0.25;     // reject a plane with more returns beyond it than this x inliers
  double inlier_threshold_m = 0.05;// inlier band for counting / rms
  int irls_iterations = 8;
  double irls_initial_scale_m = 0.2;  // first Tukey cut-off (4 x the 5 cm band that chose the start);
                                      // halves every iteration down to ~4.7 sigma
  int room_height_window = 51;     // frames in the running median of the floor-to-ceiling height
  double tight_refit_sigmas = 2.5; // ceiling refit at this many robust sigmas (0 = off), see fit_plane
};

enum class SegStatus : int8_t { kOk = 0, kNoCeiling = 1, kBadInput = 2, kEmpty = 3 };
enum class AttitudeSource : int8_t { kCeiling = 0, kPrevious = 1, kImu = 2, kNone = 3 };

struct Plane {
  Eigen::Vector4d coeffs = Eigen::Vector4d::Zero();  // n.x n.y n.z d, n.p + d = 0, n into the room
  bool found = false;
  int inliers = 0;
  int beyond = 0;           // returns behind the plane (above a ceiling / below a floor), 2x the inlier band
  double rms_m = 0.0;
  double tilt_sigma = 0.0;  // 1-sigma of the normal direction [rad] (from the inlier spread)
  double d_sigma = 0.0;     // 1-sigma of the distance [m]
  double distance() const { return coeffs[3]; }       // origin to plane [m] (n points away from it)
};

// Wall points, ring-major (scan row order), each ring in increasing destaggered column.
struct WallPoints {
  std::vector<float> x, y, z, range;
  std::vector<float> t;                 // measurement time - scan utime [s] (the column's time stamp)
  std::vector<int16_t> ring, column;
  size_t size() const { return x.size(); }
  void clear() {
    x.clear(); y.clear(); z.clear(); range.clear(); t.clear(); ring.clear(); column.clear();
  }
  void push(const Eigen::Vector3f& p, float r, int u, int c, float dt) {
    x.push_back(p.x()); y.push_back(p.y()); z.push_back(p.z()); range.push_back(r); t.push_back(dt);
    ring.push_back(int16_t(u)); column.push_back(int16_t(c));
  }
};

struct Segmentation {
  int64_t utime = 0, seq = 0;
  SegStatus status = SegStatus::kEmpty;
  std::string status_text;
  Plane ceiling, ground;
  double roll = 0, pitch = 0;        // [rad], R = Rz(yaw) Ry(pitch) Rx(roll) (sensor -> world)
  double z = 0;                      // sensor height above the floor [m]
  double roll_pitch_sigma = M_PI;    // 1-sigma [rad]; pi = unknown
  double z_sigma = 1e3;              // 1-sigma [m]
  AttitudeSource attitude_source = AttitudeSource::kNone;
  bool deskewed = false;             // planes fitted to gyro-de-skewed returns (roll/pitch/z at mid-sweep)
  // roll/pitch/z hold at utime + attitude_t [s]: mid-sweep (the returns are de-skewed to it, or the planes
  // are fitted over the whole sweep); downstream poses stamped at utime interpolate to their own time.
  double attitude_t = 0;
  int height = 0, width = 0;
  WallPoints wall;
  // Per pixel of the scan (row-major, staggered like the scan): 0 none, 1 ceiling, 2 ground, 3 wall.
  // Filled only when Segmenter::set_keep_labels(true) (bench/tests).
  std::vector<uint8_t> label;
};

// Gravity "up" direction in the sensor frame from roll/pitch and back.
Eigen::Vector3d up_from_roll_pitch(double roll, double pitch);
void roll_pitch_from_up(const Eigen::Vector3d& up, double& roll, double& pitch);

class Segmenter {
 public:
  explicit Segmenter(SegmenterConfig cfg);
  virtual ~Segmenter();
  virtual const char* name() const = 0;

  // Segments one scan. Never throws on bad data: the status says what was wrong.
  const Segmentation& process(const Scan& scan);
  const Segmentation& last() const { return out_; }

  // IMU accelerometer sample (specific force, m/s^2) in the sensor frame; averaged until the next scan.
  void add_accel(const Eigen::Vector3d& accel);
  // IMU gyro sample (rad/s, sensor frame) measured at utime [us, the scan's clock]. Samples covering a
  // sweep de-skew its rotation (config deskew_gyro); without them the scan is used as measured.
  void add_gyro(const Eigen::Vector3d& rate, int64_t utime);
  void set_keep_labels(bool on) { keep_labels_ = on; }
  const SegmenterConfig& config() const { return cfg_; }
  double room_height() const { return room_height_; }  // 0 until known
  const Eigen::Vector3d& gyro_bias() const { return gyro_bias_; }  // rad/s, perpendicular-to-gravity part
  // Last scan's points per pixel (row-major like the scan, de-skewed when last().deskewed; only pixels with a
  // return inside [min_range_m, max_range_m] are meaningful). Diagnostics.
  const std::vector<Eigen::Vector3f>& points() const { return xyz_; }

 protected:
  // Points offered to a plane fit: the upper (ceiling) or lower (ground, flipped) half rings.
  struct Candidates {
    std::vector<Eigen::Vector3f> p;  // sensor frame
    std::vector<float> range;
    std::vector<int32_t> pixel;      // row-major pixel index in the scan
    std::vector<int32_t> ring_start; // ring_start[k]..ring_start[k+1] = k-th ring from the outermost
    int width = 0;                   // columns of the scan (pixel % width = staggered column)
    int rings() const { return int(ring_start.size()) - 1; }
  };
  // Fits the dominant horizontal plane of `c` above the sensor along `up` (for the ground `up` is
  // flipped, so the same code works). `previous` (if non-null) is last frame's plane in the same
  // convention. Returns the plane with n pointing against `up` (into the room), or false.
  virtual bool fit_plane(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous,
                         Eigen::Vector4d& plane) = 0;

  SegmenterConfig cfg_;
  bool tighten_ = false;  // set while fit_plane() fits the ceiling (the plane that gives the attitude)

 private:
  bool prepare(const Scan& scan);
  bool deskew_rotations(const Scan& scan);
  static double mid_sweep_offset(const Scan& scan);
  Eigen::Vector3d gyro_at(int64_t utime) const;
  bool gyro_covers(int64_t ta, int64_t tb) const;
  Eigen::Matrix3d gyro_rotation(int64_t ta, int64_t tb) const;
  void update_gyro_bias(const Eigen::Vector3d& up);
  void quality(const Candidates& c, Plane& pl) const;
  void select_walls(const Scan& scan, const Eigen::Vector3d& up);
  void update_room_height(double h);

  Segmentation out_;
  XyzLut lut_;
  BeamIntrinsics lut_beams_;
  int lut_width_ = 0;
  std::vector<Eigen::Vector3f> xyz_;   // sensor frame (de-skewed to mid-sweep when out_.deskewed)
  std::vector<Eigen::Vector3f> raw_;   // as measured (only filled when de-skewing)
  std::vector<Eigen::Matrix3f> col_rot_;
  std::vector<float> range_;
  std::vector<float> col_dt_;  // per staggered column: column time - scan utime [s]
  std::vector<int> ring_order_;      // rings sorted by altitude, top first
  Candidates upper_, lower_;
  bool keep_labels_ = false;

  // State for fallbacks and priors.
  bool have_prev_ceiling_ = false, have_prev_ground_ = false;
  Eigen::Vector4d prev_ceiling_, prev_ground_;
  bool have_prev_attitude_ = false;
  double prev_roll_ = 0, prev_pitch_ = 0, prev_z_ = 0, prev_rp_sigma_ = 0, prev_z_sigma_ = 0;
  Eigen::Vector3d accel_sum_ = Eigen::Vector3d::Zero();
  int accel_n_ = 0;
  Eigen::Vector3d imu_up_ = Eigen::Vector3d::UnitZ();
  std::deque<std::pair<int64_t, Eigen::Vector3d>> gyro_;  // last ~1 s of gyro samples, increasing time
  Eigen::Vector3d gyro_bias_ = Eigen::Vector3d::Zero();   // estimated from consecutive ceilings
  int64_t sweep_tm_ = 0;                                  // this scan's mid-sweep time when the gyro covers it
  bool have_bias_ref_ = false;
  int64_t bias_ref_t_ = 0;
  Eigen::Vector3d bias_ref_up_ = Eigen::Vector3d::UnitZ();
  std::vector<int64_t> col_t_;
  std::vector<int> col_mid_;
  std::vector<uint8_t> col_ok_;
  bool have_imu_ = false;
  std::deque<double> heights_;
  double room_height_ = 0.0;
};

// The paper's segmenter: max-range seeds on the top K_r rings, linear regression, IRLS (Tukey).
class RingSegmenter : public Segmenter {
 public:
  using Segmenter::Segmenter;
  const char* name() const override { return "rings"; }

 protected:
  bool fit_plane(const Candidates& c, const Eigen::Vector3d& up, const Eigen::Vector4d* previous,
                 Eigen::Vector4d& plane) override;

 private:
  std::vector<int> seeds_, all_seeds_;
  std::vector<float> sector_best_;
  std::vector<int> sector_idx_;
  std::vector<Eigen::Vector3f> band_;
  std::vector<float> res_;
};

const char* to_string(SegStatus s);

}  // namespace fploc::seg
