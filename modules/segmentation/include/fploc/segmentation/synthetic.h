// Test support: ray-cast OS-1-like scans of a box room (walls, floor, ceiling) with axis-aligned boxes
// (pillars in the plan, clutter not in it), range noise and dropouts. Every pixel gets a label, so
// tests and benchmarks know the truth. Not a simulator (modules/sim is); small, exact and fast.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fploc/core/scan.h"

namespace fploc::seg::synth {

enum Label : uint8_t { kNone = 0, kCeiling = 1, kFloor = 2, kWall = 3, kClutter = 4 };

struct Box {
  Eigen::Vector3d lo, hi;
  Label label = kClutter;  // kWall for plan pillars
};

struct Room {
  double half_x = 8, half_y = 6;   // walls at x = +-half_x, y = +-half_y
  double height = 3.0;             // floor z = 0, ceiling z = height
  bool ceiling = true;             // false: open sky (no returns upwards)
  double wall_top = 0;             // walls end here (0 = at the ceiling height); an atrium: tall walls
  std::vector<Box> boxes;
  // A ramp across the room: the floor rises from 0 at x = x0 to `rise` at x = x1 and stays there (a
  // landing); the ceiling stays at `height` above z = 0. Off when x1 <= x0.
  struct Ramp {
    double x0 = 0, x1 = 0, rise = 0;
    bool ceiling_follows = false;  // the ceiling `height` above the floor everywhere (rises with the ramp)
    double landing_ceiling_slope = 0;  // with ceiling_follows: over the landing the ceiling rises this much per m of x
  } ramp;
  double floor_at(double x) const;  // floor height under x
};

struct SensorPose {
  double x = 0, y = 0, z = 1.5, roll = 0, pitch = 0, yaw = 0;  // R = Rz(yaw) Ry(pitch) Rx(roll)
};

// OS-1-64-like intrinsics: altitudes evenly from +16.6 to -16.6 deg, 4 staggered azimuth offsets.
BeamIntrinsics os1_like_beams(int beams = 64);

struct SynthScan {
  Scan scan;
  std::vector<uint8_t> label;  // per pixel, row-major like scan.range_mm
};

SynthScan render(const Room& room, const SensorPose& pose, const BeamIntrinsics& beams, int width,
                 double range_noise_m, double dropout, uint32_t seed);

// A furnished test room: two pillars (plan) and a few clutter boxes (tables, cabinets, a person).
Room furnished_room();

}  // namespace fploc::seg::synth
