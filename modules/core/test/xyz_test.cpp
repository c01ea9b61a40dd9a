#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

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

// The table computed pixel by pixel, every sine and cosine taken at the pixel (make_xyz_lut computes those of
// the encoder angle once per column and those of the altitude and azimuth once per beam, the pixel's by the
// angle sums: in double within a few 1e-16 of these, the same floats but where a value lies at a float's
// rounding edge, which none of the tables below has).
static XyzLut per_pixel_lut(const BeamIntrinsics& beams, int width) {
  XyzLut lut;
  lut.height = beams.beams();
  lut.width = width;
  const size_t n = size_t(lut.height) * width;
  lut.direction.resize(n, 3);
  lut.offset.resize(n, 3);
  const auto& T = beams.lidar_to_sensor;
  Eigen::Matrix3d R;
  R << T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10];
  const Eigen::Vector3d t(T[3], T[7], T[11]);
  const double n_mm = beams.beam_offset_mm;
  for (int u = 0; u < lut.height; ++u) {
    const double phi = beams.altitude_deg[u] * M_PI / 180.0;
    const double theta_a = -beams.azimuth_deg[u] * M_PI / 180.0;
    for (int v = 0; v < width; ++v) {
      const double theta_e = 2.0 * M_PI - v * 2.0 * M_PI / width;
      const Eigen::Vector3d d(std::cos(theta_e + theta_a) * std::cos(phi), std::sin(theta_e + theta_a) * std::cos(phi),
                              std::sin(phi));
      const Eigen::Vector3d e(std::cos(theta_e), std::sin(theta_e), 0.0);
      const Eigen::Vector3d dir = R * d;
      const Eigen::Vector3d off = R * (n_mm * e - n_mm * d) + t;
      const size_t i = size_t(u) * width + v;
      lut.direction.row(i) = (dir * 1e-3).cast<float>().transpose();
      lut.offset.row(i) = (off * 1e-3).cast<float>().transpose();
    }
  }
  return lut;
}

// Bit for bit the per-pixel table: 64 beams with their own altitudes and azimuth offsets (as a calibrated OS-1's),
// a tilted and shifted lidar frame, the usual widths and an odd one.
TEST(Xyz, TableIsThePerPixelFormulaBitForBit) {
  BeamIntrinsics b;
  for (int u = 0; u < 64; ++u) {
    b.altitude_deg.push_back(16.6 - u * 0.5234 + 0.013 * std::sin(u));
    b.azimuth_deg.push_back((u % 4 == 0 ? 3.073 : u % 4 == 1 ? 0.904 : u % 4 == 2 ? -1.261 : -3.384) + 0.0071 * u);
  }
  b.beam_offset_mm = 15.806;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.031, Eigen::Vector3d(0.3, -0.2, 1.0).normalized()).toRotationMatrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) b.lidar_to_sensor[size_t(4 * r + c)] = R(r, c);
  b.lidar_to_sensor[3] = 1.5;
  b.lidar_to_sensor[7] = -2.25;
  b.lidar_to_sensor[11] = 36.18;
  for (int W : {512, 1024, 2048, 1000}) {
    const XyzLut a = make_xyz_lut(b, W), ref = per_pixel_lut(b, W);
    ASSERT_EQ(a.direction.rows(), ref.direction.rows());
    size_t differ = 0;
    for (Eigen::Index i = 0; i < ref.direction.rows(); ++i)
      for (int e = 0; e < 3; ++e)
        differ += std::memcmp(&a.direction(i, e), &ref.direction(i, e), sizeof(float)) != 0 ||
                  std::memcmp(&a.offset(i, e), &ref.offset(i, e), sizeof(float)) != 0;
    EXPECT_EQ(differ, 0u) << "width " << W;
  }
}

TEST(Xyz, Destagger) {
  BeamIntrinsics b;
  b.pixel_shift_by_row = {18, 12, 6, 0};
  EXPECT_EQ(destagger_column(b, 0, 1020, 1024), 14);
  EXPECT_EQ(destagger_column(b, 3, 5, 1024), 5);
}
