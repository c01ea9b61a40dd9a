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
#include "fploc/floorplan/plan.h"
#include "fploc/sim/ceiling_map.h"
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
};

class Simulator {
 public:
  // An empty plan means: the demo plan of the scenario (room or corridor).
  Simulator(FloorPlan plan, SimulatorOptions opt);

  int num_frames() const { return num_frames_; }
  // Frame k starts at t0 + k / rate.
  double frame_time(int k) const { return opt_.t0_s + k / opt_.rate_hz; }
  void frame(int k, SimScan& out);
  const std::vector<ImuSample>& imu() const { return imu_; }  // t relative to t0_s
  // Ground truth at absolute time t [s].
  StampedPose ground_truth(double t) const;
  Eigen::Vector3d velocity(double t) const { return motion_->velocity(t - opt_.t0_s); }
  Eigen::Vector3d angular_velocity(double t) const { return motion_->angular_velocity_body(t - opt_.t0_s); }

  const World& world() const { return *world_; }
  World& world() { return *world_; }
  const Motion& motion() const { return *motion_; }
  const ScenarioSpec& spec() const { return spec_; }
  const LidarSim& lidar() const { return *lidar_; }
  const SimulatorOptions& options() const { return opt_; }
  const std::string& beam_source() const { return beam_source_; }
  const std::string& info() const { return info_; }  // planner / clutter notes
  // The difference between world and plan (nullptr when the world is the plan).
  const WorldEdit* world_edit() const { return edit_.get(); }
  const CeilingMap& ceiling_map() const { return ceiling_map_; }  // building-* scenarios (else empty)

 private:
  void add_clutter();
  void add_wall_clutter();
  SimulatorOptions opt_;
  ScenarioSpec spec_;
  std::unique_ptr<WorldEdit> edit_;
  std::unique_ptr<World> world_;
  std::unique_ptr<Motion> motion_;
  std::unique_ptr<LidarSim> lidar_;
  std::vector<ImuSample> imu_;
  int num_frames_ = 0;
  std::string beam_source_, info_;
  CeilingMap ceiling_map_;
};

}  // namespace fploc::sim
