// Which floor of a building the robot is on, and when it changes floor (issue 11 item 4). No LCM: the
// matcher node feeds it every frame (its pose, the segmenter's z) and the IMU, and switches its plan
// when update() returns a FloorSwitch.
//
// Cues, only inside (or within a margin of) a connection area of the current floor:
//  - STAIRS / RAMP: the climb since entering the area, from
//      (a) the segmenter's z: z is the sensor's height above the floor under it, so on a ramp it is
//          (floor's elevation + z) - (current floor's elevation) relative to the nominal sensor height z0
//          (the median z on flat floor, outside connection areas), and
//      (b) the IMU's tilt (low-passed specific force: roll/pitch against gravity) times the horizontal
//          displacement between frames along the slope it implies (independent of what the segmenter makes
//          of a sloped floor or a ceiling of the other floor).
//    The robot switches to the connected floor once either climb is past `switch_fraction` of the way to
//    that floor's elevation for `confirm_frames` frames.
//  - LIFT: the IMU's vertical motion (VerticalImu: specific force minus gravity along the vertical,
//    integrated twice between two rests). At the end of a ride the floor whose elevation difference is
//    closest to the ride's height (among floors reachable through lift connections containing the robot)
//    is the new floor, when the height is within `lift_tolerance_fraction` of that difference. The plan
//    no longer matching (the current floor's inlier ratio during the ride) is reported beside it.
// Every switch and every refused candidate has a status text; nothing switches silently.
//
// z: the segmenter does not know about floors. floor_z() turns its z into the height above the
// current floor: after a ramp/stairs switch the segmenter's z is still relative to the old floor until
// it re-learns its ceiling, so the elevation difference is carried as an offset, dropped once the
// segmenter's z is back near z0 on flat floor.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/floorplan/building.h"
#include "fploc/localizer/vertical_imu.h"

namespace fploc::localizer {

struct FloorTrackerConfig {
  double connection_margin_m = 1.0;    // a connection counts this far around its polygon
  double switch_fraction = 0.5;        // stairs/ramp: switch when the climb is past this part of the way
  int confirm_frames = 3;              // ... for this many consecutive frames
  double switch_back_margin = 0.15;    // back to the floor left in the same visit of the area: this much further
  int nominal_z_frames = 50;           // z0 = median of the last this many flat-floor z (>= 10 needed)
  double z_offset_drop_m = 0.25;       // the segmenter's z within this of z0 on flat floor: offset dropped
  double lift_min_height_m = 0.5;      // a ride below this is no floor change (noise, a lift's levelling)
  double lift_tolerance_fraction = 0.3;  // |ride - elevation difference| <= this * |difference|
  double lift_max_speed_mps = 0.15;    // the IMU's vertical motion counts only while the robot stands this still
  double tilt_lowpass_s = 0.3;         // IMU tilt: time constant of the specific force's low-pass
  double max_tilt_rad = 0.35;          // a steeper "slope" (e.g. a bump, a jolt) is not integrated
  VerticalImuConfig vertical;
};

// One frame's observation.
struct FloorObservation {
  int64_t utime = 0;
  Pose2 pose;                          // where the matcher put the frame (x, y, yaw)
  bool pose_ok = true;                 // the matcher's status is OK (not POOR/LOST)
  double inlier_ratio = 1;             // the matcher's inlier ratio (0..1): how well the plan matches
  double z = 0;                        // the segmenter's z (its own reference)
  bool z_known = false;
  double roll = 0, pitch = 0;          // the frame's attitude (used when there is no IMU)
  bool roll_pitch_known = false;
};

struct FloorSwitch {
  int from = 0, to = 0;                // floor indices
  std::string from_name, to_name;
  FloorConnection via;                 // the connection used (its polygon: where to relocalize)
  std::string reason;                  // e.g. "lift 'lift': IMU vertical motion +3.28 m ..."
  // Where to look on the new floor: the connection polygon's centroid and the radius of a disc holding
  // it (plus the margin).
  Eigen::Vector2d search_center = Eigen::Vector2d::Zero();
  double search_radius_m = 0;
};

class FloorTracker {
 public:
  // `initial_floor`: index into building->floors.
  FloorTracker(std::shared_ptr<const Building> building, int initial_floor, FloorTrackerConfig cfg = {});

  int floor() const { return floor_; }
  const std::string& floor_name() const;
  const Building& building() const { return *building_; }

  // Accelerometer sample (specific force in the sensor frame, m/s^2; the IMU's axes are taken as the
  // sensor's, as the matcher does for the gyro).
  void add_imu(int64_t utime, const Eigen::Vector3d& accel);
  // One frame; a switch when the robot changed floor (the tracker is then on the new floor).
  std::optional<FloorSwitch> update(const FloorObservation& o);
  // An operator (or a relocalization) puts the robot on a floor; the reason goes to the status text.
  void set_floor(int floor, const std::string& reason);

  // The segmenter's z as the height above the current floor (see above).
  double floor_z(double z) const { return z - z_offset_; }
  double z_offset() const { return z_offset_; }
  std::optional<double> nominal_z() const { return z0_; }
  // What the tracker last decided or noticed ("" while nothing happened).
  const std::string& status_text() const { return text_; }

  // The disc around a polygon (centroid, farthest vertex + margin).
  static void search_disc(const std::vector<Eigen::Vector2d>& polygon, double margin, Eigen::Vector2d* c, double* r);

 private:
  bool near(const FloorConnection& c, const Eigen::Vector2d& p) const;
  std::optional<FloorSwitch> check_lift(const FloorObservation& o, const VerticalRide& ride);
  std::optional<FloorSwitch> check_climb(const FloorObservation& o);
  FloorSwitch make_switch(int to, const FloorConnection& via, const std::string& reason);

  std::shared_ptr<const Building> building_;
  FloorTrackerConfig cfg_;
  int floor_ = 0;
  VerticalImu vertical_;
  // IMU tilt (low-passed specific force).
  bool have_f_ = false;
  int64_t last_imu_utime_ = 0;
  Eigen::Vector3d f_lp_ = Eigen::Vector3d::Zero();
  // Flat-floor z (nominal sensor height) and the offset after a ramp/stairs switch.
  std::deque<double> flat_z_;
  std::optional<double> z0_;
  double z_offset_ = 0;
  // Stairs/ramp: the climb since entering the connection area.
  bool in_climb_area_ = false;
  bool have_prev_ = false;
  Pose2 prev_pose_;
  double enter_elevation_ = 0;         // the floor's elevation when the robot entered the area
  double tilt_climb_ = 0;              // since entering (IMU tilt x travel)
  bool tilt_valid_ = false;            // an attitude was known for the integration
  bool switched_in_area_ = false;
  int confirm_ = 0, confirm_to_ = -1;
  // Lift: the inlier ratio while riding.
  bool in_lift_ = false;
  bool have_lift_prev_ = false;
  int64_t lift_prev_utime_ = 0;
  Pose2 lift_prev_;
  double ride_inliers_sum_ = 0;
  int ride_frames_ = 0;
  double before_inliers_ = 1;
  std::string text_;
};

}  // namespace fploc::localizer
