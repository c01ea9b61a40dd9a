// One simulated sequence: plan -> 3D world (+ clutter) -> trajectory for a named scenario -> LiDAR frames,
// IMU samples and ground truth. Transport-free (the sim tool writes an LCM log, the sim-sensor node sends
// OS-1 UDP packets). Deterministic for (plan, scenario, seed, options).
//
//   fploc::sim::SimulatorOptions o; o.scenario = "room-small-loop-medium"; o.seed = 1;
//   fploc::sim::Simulator sim(fploc::sim::demo_room_plan(), o);
//   fploc::sim::SimScan f;
//   for (int k = 0; k < sim.num_frames(); ++k) { sim.frame(k, f); ... f.scan, f.label, f.gt ... }
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/floorplan/building.h"
#include "fploc/floorplan/plan.h"
#include "fploc/sim/building_world.h"
#include "fploc/sim/ceiling_map.h"
#include "fploc/sim/journey.h"
#include "fploc/sim/motion.h"
#include "fploc/sim/perturb.h"
#include "fploc/sim/planner.h"
#include "fploc/sim/scenarios.h"
#include "fploc/sim/sensor.h"
#include "fploc/sim/world.h"

namespace fploc::sim {

struct SimulatorOptions {
  std::string scenario = "room-small-loop-medium";
  uint64_t seed = 0;
  bool clutter = true;            // furniture boxes and walking people (not in the plan)
  double wall_clutter = 0;        // fraction of the wall length hidden behind 2 m tall cabinets (robustness)
  bool ceiling_patches = true;    // a sloped and a missing ceiling patch (room scenarios and auto-loop)
  double ceiling_height_m = 0;    // 0 = scenario default
  double range_noise_m = 0.02;
  double dropout = 0.01;
  std::string metadata;           // Ouster metadata JSON for the beams ("" = `beams`)
  std::string beams;              // beam pattern (beam_patterns.h: os1-64, os1-32, os1-128, vlp16; "" = os1-64)
  std::string shared_dir;         // where ../shared is ("" = no shared data: nominal beams)
  double imu_rate_hz = 100;       // the OS-1's own IMU runs at 100 Hz
  double t0_s = 1700000000.0;     // time of the first sample [s] (absolute, written into messages)
  int width = 1024;
  double rate_hz = 10;
  // World != plan (perturb.h): seeded perturbations of the plan, or a world file; the plan still gives
  // the scenario's path. Empty = the world is the plan.
  PerturbOptions perturb;
  std::string world_file;
  std::vector<std::string> world_layers;
  std::string world_units;
  bool thresholds = true;         // buildings: 2-3 cm thresholds across the plans' doorways
};

class Simulator {
 public:
  // An empty plan means: the demo plan of the scenario (room or corridor).
  Simulator(FloorPlan plan, SimulatorOptions opt);
  // A building (fploc/floorplan/building.h): the floor the sensor is on is simulated (its plan as walls,
  // its ceilings, ramps/stairs and door thresholds, building_world.h); poses are absolute (z = floor
  // elevation + height above it). Journey scenarios (building-twofloor|ramp|thresholds-*) change floor
  // on the ramp and in the lift; any other scenario stays on `floor` ("" = the first floor).
  // `plan_options` (layers, units) apply to every floor's plan.
  Simulator(const Building& building, const std::string& floor, SimulatorOptions opt, const PlanLoadOptions& plan_options = {});

  int num_frames() const { return num_frames_; }
  // Frame k starts at t0 + k / rate.
  double frame_time(int k) const { return opt_.t0_s + k / opt_.rate_hz; }
  void frame(int k, SimScan& out);
  const std::vector<ImuSample>& imu() const { return imu_; }  // t relative to t0_s
  // Ground truth at absolute time t [s].
  StampedPose ground_truth(double t) const;
  // The ground-truth floor at absolute time t (index into building().floors; 0 without a building), its
  // name ("" without a building), and what the sensor is doing: drive | ramp | lift | lift-closed | lift-moving.
  int floor_at(double t) const;
  std::string floor_name(int floor) const;
  std::string state_at(double t) const;
  // Floor changes of a journey (times relative to t0_s); empty otherwise.
  std::vector<FloorChange> floor_changes() const;
  const Building* building() const { return building_ ? building_.get() : nullptr; }
  // Buildings: the world of floor i (null when that floor is not simulated).
  const World* floor_worlds_for_test(int i) const { return floor_worlds_.at(size_t(i)).get(); }
  Eigen::Vector3d velocity(double t) const { return motion_->velocity(t - opt_.t0_s); }
  Eigen::Vector3d angular_velocity(double t) const { return motion_->angular_velocity_body(t - opt_.t0_s); }

  const World& world() const { return *world_; }
  World& world() { return *world_; }
  const SensorTrajectory& motion() const { return *motion_; }
  const Journey* journey() const { return journey_; }
  const ScenarioSpec& spec() const { return spec_; }
  const LidarSim& lidar() const { return *lidar_; }
  const SimulatorOptions& options() const { return opt_; }
  const std::string& beam_source() const { return beam_source_; }
  const std::string& info() const { return info_; }  // planner / clutter notes
  // The difference between world and plan (nullptr when the world is the plan).
  const WorldEdit* world_edit() const { return edit_.get(); }
  const CeilingMap& ceiling_map() const { return ceiling_map_; }  // building-* scenarios (else empty)

 private:
  void init(FloorPlan plan);
  void init_building(const PlanLoadOptions& plan_options);
  void finish();
  void add_clutter(World& w, const std::vector<Eigen::Vector2d>& path, double len, uint64_t salt, int* boxes, int* people);
  void add_clutter();
  // The world the sensor is in at absolute time t and the height of that world's z = 0.
  World& world_at(double t, double* z0);
  void add_wall_clutter();
  SimulatorOptions opt_;
  ScenarioSpec spec_;
  std::unique_ptr<WorldEdit> edit_;
  std::unique_ptr<World> own_world_;
  World* world_ = nullptr;             // own_world_, or the start floor's world of a building
  std::unique_ptr<SensorTrajectory> motion_;
  const Journey* journey_ = nullptr;  // motion_ when it is a journey
  std::shared_ptr<Building> building_;
  int floor_ = 0;                      // the floor simulated (single-floor runs) / the start floor
  std::vector<std::unique_ptr<World>> floor_worlds_;  // buildings: one per floor (null when not needed)
  std::vector<FloorGround> grounds_;
  std::vector<std::unique_ptr<World>> lift_worlds_;    // per connection (null unless a lift)
  std::unique_ptr<LidarSim> lidar_;
  std::vector<ImuSample> imu_;
  int num_frames_ = 0;
  std::string beam_source_, info_;
  CeilingMap ceiling_map_;
};

}  // namespace fploc::sim
