// What the segmenter outputs for one scan: the ceiling and ground planes, the gravity-aligned part of the
// pose (roll, pitch, height) with its sources and sigmas, and the wall points.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace fploc::seg {

enum class SegStatus : int8_t { kOk = 0, kNoCeiling = 1, kBadInput = 2, kEmpty = 3 };
// kSlope: the planes' attitude turned by the slope of the surfaces they are on (ramps: the IMU's gravity against
// the planes, gravity_fusion.h); kGyro: no plane, gravity carried by the gyro from the last scan.
enum class AttitudeSource : int8_t { kCeiling = 0, kPrevious = 1, kImu = 2, kNone = 3, kGround = 4, kSlope = 5, kGyro = 6 };
// Where z came from: the ceiling with the floor-to-ceiling height of the area (configured, or learned online
// from ceiling + ground), the floor plane, a prediction (the last estimate, sigma grown; no trustworthy
// plane or a jump not confirmed by the other plane), or nothing yet.
enum class HeightSource : int8_t { kCeiling = 0, kGround = 1, kPredicted = 2, kNone = 3 };
const char* to_string(AttitudeSource s);
const char* to_string(HeightSource s);

struct Plane {
  Eigen::Vector4d coeffs = Eigen::Vector4d::Zero();  // n.x n.y n.z d, n.p + d = 0, n into the room
  bool found = false;
  int inliers = 0;
  int beyond = 0;           // returns behind the plane (above a ceiling / below a floor), 2x the inlier band
  double rms_m = 0.0;
  double tilt_sigma = 0.0;  // 1-sigma of the normal direction [rad] (from the inlier spread)
  double d_sigma = 0.0;     // 1-sigma of the distance [m]
  double distance() const { return coeffs[3]; }       // origin to plane [m] (n points away from it)
  // Ground only: the sensor's height above the surface under it when the plane is another surface seen beside
  // it (a ramp's foot or head, ground_kink.cpp); 0: the plane's own distance.
  double under_m = 0.0;
  double height() const { return under_m > 0 ? under_m : coeffs[3]; }
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
  // Appends what was noticed to status_text ("; " between notes).
  void note(const std::string& what) {
    if (!status_text.empty()) status_text += "; ";
    status_text += what;
  }
  Plane ceiling, ground;
  double roll = 0, pitch = 0;        // [rad], R = Rz(yaw) Ry(pitch) Rx(roll) (sensor -> world)
  double z = 0;                      // sensor height above the floor [m]
  double roll_pitch_sigma = M_PI;    // 1-sigma [rad]; pi = unknown
  double z_sigma = 1e3;              // 1-sigma [m]
  AttitudeSource attitude_source = AttitudeSource::kNone;
  HeightSource z_source = HeightSource::kNone;
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

// Gravity "up" direction in the sensor frame from roll/pitch and back.
Eigen::Vector3d up_from_roll_pitch(double roll, double pitch);
void roll_pitch_from_up(const Eigen::Vector3d& up, double& roll, double& pitch);

const char* to_string(SegStatus s);

}  // namespace fploc::seg
