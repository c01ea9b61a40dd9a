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
// z (the pose's z is ABSOLUTE: the current floor's elevation + the sensor's height above that floor's
// level; continuous across ramps, stairs and lifts; elevation 0 for a single plan, so nothing changes
// there): the segmenter does not know about floors, and its z may be the height above the surface under
// the robot (floor plane, a ceiling parallel to a ramp) or above a floor's level (a ceiling area of the
// building, a flat ceiling over a ramp), possibly still the floor just left. pose_z() picks, per frame, the
// reference that puts the sensor nearest its nominal height z0 above the surface the building's geometry
// (fploc/floorplan/incline.h) gives under the robot: that floor's level, the incline's surface, or the
// level of the floor left at the last ramp/stairs switch. A segmenter's z still further than z_gate_m from
// z0 above that surface is not used (the prediction instead, grown sigma, said in the status text). While riding a lift the height is z0 + the IMU's
// vertical motion since the ride started (z sigma grown by the double integration); on arrival it snaps to
// the new floor's elevation + the segmenter's z, said in status_text().
//
// Plan mismatch (no IMU, or an IMU that saw no ride): standing in a lift area, the current floor's plan
// no longer matches for `mismatch_frames` frames -> probe_request() names the floors reachable through the
// lift; the matcher node registers the frame on each (and on the current floor, the same search disc) and
// hands the inlier ratios to probe_result(), which switches to the best one when it clearly beats the
// current floor.
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
#include "fploc/floorplan/incline.h"
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
  double ride_accel_sigma_mps2 = 0.02; // lift: residual vertical acceleration error (z sigma 0.5 a t^2)
  double max_ride_z_sigma_m = 0.5;     // ... at most (z stays "known": below 1 m)
  double z_reference_hysteresis_m = 0.02;  // the segmenter's z reference changes when better by this much
  double z_gate_m = 0.08;              // the segmenter's z this far from z0 above the surface: not used ...
  double z_gated_sigma_m = 0.03;       // ... the prediction instead, with this sigma: the last good height above
  double z_hold_s = 5.0;               // the surface when it is this recent, else the nominal z0
  // A step: the segmenter's height above the surface under the sensor further than z_step_gate_m from the
  // last good one (at most z_step_window_s old) is not used (the last good height instead, z_gated_sigma_m)
  // until z_step_confirm_frames frames in a row agree on the new height (within the gate). A door sill
  // lifts the sensor by less in a frame; the height of a robot's mast changes by ~1 cm/s at most.
  double z_step_gate_m = 0.03;
  double z_step_window_s = 1.5;
  int z_step_confirm_frames = 3;
  // Plan mismatch in a lift area (floor switch without the IMU).
  double mismatch_ratio = 0.6;         // inlier ratio below this (or LOST): the plan does not match
  int mismatch_frames = 3;             // ... for this many frames in a row
  int probe_every_frames = 5;          // probe the other floors at most every this many frames
  double probe_min_ratio = 0.7;        // a floor's plan matches when its inlier ratio is at least this ...
  double probe_margin = 0.15;          // ... and beats the current floor's (same search) by this
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
  double z_sigma = 0;                  // ... and its sigma (a held prediction's is large)
  double roll = 0, pitch = 0;          // the frame's attitude (used when there is no IMU)
  bool roll_pitch_known = false;
  double attitude_t = 0;               // z holds at utime + this (mid-sweep; the lift ride's z is given there)
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

// Plan mismatch in a lift area: the floors whose plans to try (the current floor first), each with the
// search disc of the connection area.
struct FloorProbe {
  int floor = 0;
  std::string name;
  int connection = -1;                 // index into building.connections (-1: the current floor)
  Eigen::Vector2d search_center = Eigen::Vector2d::Zero();
  double search_radius_m = 0;
};
struct FloorProbeResult {
  int floor = 0;
  bool ok = false;                     // the registration's status was OK
  double inlier_ratio = 0;
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

  // The segmenter's z as the height above the current floor (see above); while riding a lift the cab
  // moves with the sensor, so the IMU's height since the ride started is added.
  // On stairs/a ramp whose z the segmenter takes from the sloped floor itself (it does not follow the
  // climb), the IMU tilt's climb relative to the current floor is added.
  // (Relative to the current floor: the climb cue's view of the segmenter's z.)
  double floor_z(double z) const {
    return z - z_offset_ + (in_lift_ && vertical_.riding() ? vertical_.height() : 0.0) + ramp_z_;
  }
  // The pose's absolute z for the last update()'s frame (see above), and its sigma given the segmenter's.
  double pose_z() const { return pose_z_; }
  double pose_z_sigma(double segmenter_sigma) const;
  // Where the last frame's z came from ("segmenter (above floor 'first')", "segmenter (above ramp 'ramp'
  // surface)", "building: nominal height ... (the segmenter's z is +0.15 m off)", "lift ride (IMU)", "held").
  const std::string& z_source() const { return z_source_; }
  double z_offset() const { return z_offset_; }
  // Plan mismatch: the floors to try for the last update()'s frame (empty: nothing to do), and their
  // results (the current floor's first); a switch when one clearly matches better.
  const std::vector<FloorProbe>& probe_request() const { return probe_; }
  std::optional<FloorSwitch> probe_result(const std::vector<FloorProbeResult>& results);
  std::optional<double> nominal_z() const { return z0_; }
  // What the tracker last decided or noticed ("" while nothing happened).
  const std::string& status_text() const { return text_; }

  // The disc around a polygon (centroid, farthest vertex + margin).
  static void search_disc(const std::vector<Eigen::Vector2d>& polygon, double margin, Eigen::Vector2d* c, double* r);

 private:
  bool near(const FloorConnection& c, const Eigen::Vector2d& p) const;
  std::optional<FloorSwitch> check_lift(const FloorObservation& o, const VerticalRide& ride);
  std::optional<FloorSwitch> check_climb(const FloorObservation& o);
  std::optional<FloorSwitch> update_floor(const FloorObservation& o);
  void resolve_z(const FloorObservation& o, const std::optional<FloorSwitch>& s);
  // The ramp/stairs of the current floor under p: its surface's height above the floor's level there, and
  // 1 / cos of its slope.
  struct InclineAt {
    double g = 0, inv_cos = 1;
    std::string name;
  };
  std::optional<InclineAt> incline_under(const Eigen::Vector2d& p) const;
  void check_mismatch(const FloorObservation& o, bool switched);
  std::vector<int> lift_reachable(const Eigen::Vector2d& p, std::vector<int>* via) const;
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
  double ramp_z_ = 0;                  // the climb floor_z adds (see there)
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
  // Pose z.
  std::vector<Incline> inclines_;
  double pose_z_ = 0, h_ = 0;
  bool have_h_ = false;
  int z_ref_kind_ = 0;
  bool z_gated_ = false;                 // 0 floor level, 1 incline surface, 2 level of the floor left
  std::string z_source_ = "floor";
  int step_frames_ = 0;                // frames in a row whose height stepped away from the last good one
  double step_above_ = 0;              // ... the last one's height above the surface
  double ride_base_ = 0;               // lift: the height above the floor when the ride started
  bool ride_active_ = false;
  double good_h_ = 0;                  // the last height above a flat floor the segmenter measured (not gated)
  int64_t good_h_utime_ = 0;
  bool have_good_h_ = false;
  double above_ = 0;                   // the last good (not gated) height above the surface under the robot
  int64_t above_utime_ = 0;
  bool have_above_ = false;
  int64_t last_utime_ = 0;
  // Plan mismatch.
  int mismatch_ = 0, since_probe_ = 0;
  Eigen::Vector2d mismatch_at_ = Eigen::Vector2d::Zero();
  std::vector<FloorProbe> probe_;
};

}  // namespace fploc::localizer
