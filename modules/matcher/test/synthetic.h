// Synthetic plans and 2D feature frames for the localization tests and benchmarks: a room with
// pillars and a ray-casting "sensor" that produces features from a known pose, with range noise,
// clutter that is not in the plan, and PCA group ids (consecutive hits on one wall).
#pragma once
#include <cstdint>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/matcher/types.h"

namespace fploc::testing {

// ~20 x 10 m room, door gaps on two opposite walls, a square and two round pillars.
FloorPlan room_with_pillars();
// Four bended, self-similar corridors (~2 m wide) around a block.
FloorPlan corridor_loop();
// A straight corridor 2 m wide along x (walls y = 0 and y = 2, 200 m long): with a short max_range its
// ends are never seen, so nothing in the plan fixes x.
FloorPlan endless_corridor();

struct SynthOptions {
  int beams = 360;             // rays over 360 degrees
  double max_range = 25.0;
  double noise_sigma = 0.0;    // range noise [m]
  double clutter_fraction = 0; // extra points not on the plan, as a fraction of the hits
  double clutter_radius = 4.0; // clutter points lie within this distance of the sensor
  bool groups = true;          // group ids for runs of >= 5 hits on one segment
  uint32_t seed = 1;
  // Rotating sensor: beam i is measured at t = sweep_s * i / beams after utime, from the pose
  // pose (+) matcher::exp_twist(sweep_twist, t), in the sensor frame of that moment (Feature2::t = t).
  double sweep_s = 0;
  matcher::Twist2 sweep_twist;
};

// Features as the sensor at `pose` (its pose at utime) would see them (sensor frame).
FeatureFrame synth_frame(const FloorPlan& plan, const Pose2& pose, const SynthOptions& o, int64_t utime = 0);

// Random points unrelated to the plan (a frame that cannot match).
FeatureFrame random_frame(int n, double radius, uint32_t seed);

}  // namespace fploc::testing
