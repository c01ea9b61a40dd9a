#include <gtest/gtest.h>

#include "fploc/core/xyz.h"

using namespace fploc;

// The Ouster model by hand for a beam with no azimuth offset and no beam offset: a range r at
// measurement id 0 points along +x of the lidar frame, i.e. -x of the sensor frame (default transform).
TEST(Xyz, MatchesManualFormula) {
  BeamIntrinsics b;
  b.altitude_deg = {10.0, 0.0, -10.0};
  b.azimuth_deg = {0.0, 3.0, -3.0};
  b.beam_offset_mm = 12.163;
  const int W = 1024;
  auto lut = make_xyz_lut(b, W);
  for (int u = 0; u < 3; ++u) {
    for (int v : {0, 100, 511, 1023}) {
      const double r = 5000.0, n = b.beam_offset_mm;
      const double te = 2 * M_PI - v * 2 * M_PI / W, ta = -b.azimuth_deg[u] * M_PI / 180,
                   phi = b.altitude_deg[u] * M_PI / 180;
      double x = (r - n) * std::cos(te + ta) * std::cos(phi) + n * std::cos(te);
      double y = (r - n) * std::sin(te + ta) * std::cos(phi) + n * std::sin(te);
      double z = (r - n) * std::sin(phi);
      // lidar_to_sensor default: x -> -x, y -> -y, z + 36.18 mm
      Eigen::Vector3d expect(-x * 1e-3, -y * 1e-3, (z + 36.18) * 1e-3);
      auto p = lut_point(lut, u, v, 5000);
      EXPECT_NEAR((p.cast<double>() - expect).norm(), 0, 2e-6) << u << " " << v;
    }
  }
  EXPECT_TRUE(lut_point(lut, 0, 0, 0).hasNaN());
}

TEST(Xyz, Destagger) {
  BeamIntrinsics b;
  b.pixel_shift_by_row = {18, 12, 6, 0};
  EXPECT_EQ(destagger_column(b, 0, 1020, 1024), 14);
  EXPECT_EQ(destagger_column(b, 3, 5, 1024), 5);
}
