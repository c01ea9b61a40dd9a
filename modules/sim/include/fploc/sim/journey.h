// A journey through a building: legs driven on the floors (each an open B-spline Motion from rest to
// rest, its wheels on the floor's ground: ramps, thresholds), joined by lift rides. A leg may change floor
// on a ramp (the floor switches where the path crosses the ramp's middle); a lift ride joins the end of
// one leg (inside a LIFT connection polygon) to the start of the next on another floor:
//
//   arrive, stand: doors close (doors_s / 2 after arriving) -> the car accelerates (a(t) = A sin^2, jerk
//   limited), cruises, decelerates -> arrives (the ground-truth floor switches here) -> doors open
//   doors_s / 2 later -> the next leg starts doors_s after arriving.
//
// Poses are absolute: z = floor elevation + height above that floor (the IMU sees the car's vertical
// acceleration). Deterministic for (building, legs, speed, seed).
#pragma once
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "fploc/floorplan/building.h"
#include "fploc/sim/building_world.h"
#include "fploc/sim/motion.h"

namespace fploc::sim {

struct JourneyLeg {
  std::string floor;                      // the floor the leg starts on
  std::vector<Eigen::Vector2d> control;   // open B-spline control polygon (building x/y frame)
};

struct LiftConfig {
  double accel_mps2 = 0.8;   // peak acceleration (passenger lifts: 0.5-1.0 m/s^2)
  double v_max = 1.0;        // rated speed (lowered for short rides)
  double doors_s = 3.0;      // standing with doors closing before the ride, and opening after it
  double car_height_m = 2.4;
};

// Vertical motion of a lift ride of height `rise` (signed): jerk-limited S-curve.
struct LiftProfile {
  double rise = 0, accel = 0.8, v = 1.0, t_acc = 0, t_cruise = 0;
  LiftProfile() = default;
  LiftProfile(double rise, const LiftConfig& c);
  double duration() const { return 2 * t_acc + t_cruise; }
  double z(double t) const;      // offset from the start, 0 .. rise
  double accel_at(double t) const;
};

struct FloorChange {
  double t = 0;                 // journey time [s] of the switch (ramp: the middle; lift: the car stops)
  int from = -1, to = -1;
  std::string how;              // "ramp NAME" | "lift NAME"
};

class Journey : public SensorTrajectory {
 public:
  // `grounds[i]`: the ground of floor i (make_floor_world), for the wheels.
  Journey(const Building& b, const std::vector<JourneyLeg>& legs, SpeedSpec speed, uint64_t seed,
          std::vector<FloorGround> grounds, LiftConfig lift = {});
  Journey(const Journey&) = delete;
  Journey& operator=(const Journey&) = delete;

  double duration() const override { return duration_; }
  double moving_time() const override;
  double length() const override;
  double max_speed() const override;
  Eigen::Isometry3d pose(double t) const override;
  std::vector<Eigen::Vector2d> sample_path(double ds) const override;
  std::vector<Eigen::Vector2d> sample_path_on_floor(int floor, double ds) const;

  // The floor the sensor is on at time t (ground truth), and whether it is in a closed lift car (then
  // `lift` is the connection index and `car_floor_z` the car floor's absolute height).
  int floor_at(double t) const;
  bool in_closed_lift(double t, int* lift = nullptr, double* car_floor_z = nullptr) const;
  // "drive", "ramp" (on an incline), "lift" (standing in the car, doors open), "lift-closed", "lift-moving".
  std::string state_at(double t) const;
  const std::vector<FloorChange>& floor_changes() const { return changes_; }
  int start_floor() const;

 private:
  struct Leg {
    std::unique_ptr<Motion> motion;
    int floor0 = 0;
    std::vector<std::pair<double, int>> switches;  // (arc length, floor from there on)
    double t_start = 0;
    int floor_at_s(double s) const;
  };
  struct Ride {
    int lift = -1;           // connection index
    int from = -1, to = -1;
    double t_arrive = 0;     // journey time the previous leg ends (car reached, standing)
    double t_move = 0;       // the car starts
    LiftProfile profile;
    double z_from = 0;       // car floor absolute height at the start
  };
  Building b_;
  std::vector<FloorGround> grounds_;
  std::vector<Leg> legs_;
  std::vector<Ride> rides_;
  std::vector<FloorChange> changes_;
  LiftConfig lift_;
  double duration_ = 0;
};

}  // namespace fploc::sim
