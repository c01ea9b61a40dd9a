// The ground-at-a-kink's point loops (ground_kink.cpp): which lower candidates lie near the ring fit's plane and
// in which azimuth sector x horizontal-distance band (cells()), and which grouped returns lie near a plane
// (near_plane()); internal header. Four lanes (simd4.h) or scalar, or eight with AVX2 where kern::wide()
// (compiled for AVX2 alone, no fused multiply-add: the same floats and comparisons, so the same points bit
// for bit).
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>

namespace fploc::seg::kink {

constexpr int kAzimuths = 24;             // azimuth sectors of 15 deg (a 2.5 m ramp 4 m ahead: 35 deg) ...
constexpr std::array<float, 3> kBandEdgesM{6.f, 9.f, 14.f};  // ... times horizontal-distance bands (a kink ahead)
constexpr int kCells = kAzimuths * int(kBandEdgesM.size() + 1);
constexpr float kSectorBandM = 0.3f;      // returns this near the ring fit's plane

// The cells of the points i < n (x/y/z readable up to n rounded up to 4: the candidates' NaN padding). A point
// within kSectorBandM of the plane n0.p + d0 = 0 (false for NaN) is in cell band * kAzimuths + azimuth, the
// azimuth sector as floor((atan2(y, x) + pi) / (2 pi) kAzimuths) (by quadrant and the tangents of the sector
// edges: a point within float rounding of an edge may fall on either side) and the band by its distance from
// the sensor along the plane. Those points' indices go to `index` and their cells to `cell`, in order (both
// need room for n rounded up to 8, plus 8); count[c] gains each point of cell c. Returns how many points have a
// cell.
// Tests: whether the eight-lane loop runs where kern::wide() (x86-64 with GCC/Clang and not switched off), and
// switching it off (the four-lane loop runs) or on again.
bool wide_available();
void set_wide_enabled(bool on);

size_t cells(const float* x, const float* y, const float* z, size_t n, const Eigen::Vector3f& n0, float d0,
             int32_t* index, int16_t* cell, std::array<int32_t, kCells>& count);

// The points i < n within `cut` of the plane nrm.p + d = 0 (|nrm.p + d| < cut in float, nrm.p summed as Eigen's
// dot of two Vector3f: x n_x + (y n_y + z n_z)), written to ox/oy/oz from slot m on, in order; returns m plus
// their count. Reads x/y/z up to n rounded up to 8 (a block of the grouped cells: padded with far points);
// writes up to 7 slots past the returned count.
size_t near_plane(const float* x, const float* y, const float* z, size_t n, const Eigen::Vector3f& nrm, float d,
                  float cut, float* ox, float* oy, float* oz, size_t m);

}  // namespace fploc::seg::kink
