// Simulated Ouster OS-1: ray-casts every pixel of a 1024x10 (or other) frame with Ouster's beam model
// (the same XYZ look-up table the driver uses, so range r along pixel (u, v) reproduces the point exactly),
// with the sensor moving during the sweep (per-column pose), Gaussian range noise, dropouts and max range.
#pragma once
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fploc/core/pose.h"
#include "fploc/core/scan.h"
#include "fploc/core/xyz.h"
#include "fploc/os1/metadata.h"
#include "fploc/sim/world.h"

namespace fploc::sim {

// A nominal OS-1-64 beam pattern generated in code (gen-1 OS-1-64: altitudes +16.6..-16.6 deg, the
// four-fold azimuth stagger +3.1/+0.9/-1.3/-3.4 deg, pixel shifts 19/13/6/0 for 1024 columns).
BeamIntrinsics nominal_os1_64();

// Reads beam angles, beam offset, lidar_to_sensor and pixel shifts from an Ouster metadata JSON with the
// OS-1 driver's reader (fploc/os1/metadata.h). Returns false with a message naming the file and field.
bool load_beam_intrinsics_json(const std::string& path, BeamIntrinsics& out, std::string* error);

// The SensorInfo the OS-1 driver needs to decode the simulator's packets (legacy profile, 16 columns per
// packet, lidar_mode "<width>x<rate>", the simulator's beams), and the metadata JSON (legacy flat layout)
// that describes it, for `fploc-os1-driver --metadata`.
os1::SensorInfo sensor_info_for(const BeamIntrinsics& beams, int width = 1024, double rate_hz = 10);
std::string metadata_json(const os1::SensorInfo& info);

// The beams the simulator uses by default: the real OS-1-64 calibration from
// <shared>/data/ouster/metadata/ when that folder is present, otherwise nominal_os1_64().
// `source` says which one was used.
BeamIntrinsics default_beams(const std::string& shared_dir, std::string* source);

struct SensorConfig {
  BeamIntrinsics beams = nominal_os1_64();
  int width = 1024;                // columns per frame (512/1024/2048)
  double rate_hz = 10;             // frames per second
  double range_noise_m = 0.02;     // Gaussian sigma
  double dropout = 0.01;           // fraction of returns randomly lost
  double grazing_dropout_deg = 80; // returns at a larger incidence angle are lost
  double max_range_m = 120;
  double min_range_m = 0.3;        // the OS-1 reports no return below this
};

// One simulated frame with per-pixel ground truth.
struct SimScan {
  Scan scan;                       // staggered range image [beam][measurement id], like the driver's output
  std::vector<uint8_t> label;      // Label per pixel (kNone where range_mm == 0)
  std::vector<int32_t> element;    // plan element id (walls/pillars), clutter index, or -1, per pixel
  std::vector<float> true_range_m; // noise-free range per pixel (0 where nothing was hit)
  StampedPose gt;                  // sensor pose at the frame's first column time
};

using PoseFn = std::function<Eigen::Isometry3d(double t)>;

class LidarSim {
 public:
  explicit LidarSim(SensorConfig cfg);
  const SensorConfig& config() const { return cfg_; }
  const XyzLut& lut() const { return lut_; }
  // Simulates the frame whose first column is at time t0 [s]; column v is at t0 + v / (rate * width).
  // `pose(t)` is the sensor pose (sensor frame -> world). Noise is drawn from `seed`.
  void simulate(World& world, const PoseFn& pose, double t0, int64_t frame_index, uint64_t seed, SimScan& out) const;

 private:
  SensorConfig cfg_;
  XyzLut lut_;
};

}  // namespace fploc::sim
