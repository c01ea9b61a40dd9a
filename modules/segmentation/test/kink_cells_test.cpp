// The ground-at-a-kink's cells (src/kink_cells.h): the eight-lane loop gives the four-lane loop's cells bit for
// bit, and both put a point where its azimuth and distance say (away from the edges, where float rounding may
// pick either side).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "../src/kink_cells.h"
#include "../src/plane_kernels.h"

using namespace fploc::seg;

namespace {

struct Cloud {
  std::vector<float> x, y, z;
  size_t n = 0;
};

// n points around a level floor 1.2 m below the sensor (some off it, some NaN), NaN-padded to a multiple of 4 as
// the candidates are.
Cloud floor_points(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> az(-float(M_PI), float(M_PI)), dist(0.5f, 20.f), off(-0.5f, 0.5f), u(0.f, 1.f);
  Cloud c;
  c.n = n;
  for (size_t i = 0; i < n; ++i) {
    const float a = az(rng), r = dist(rng);
    c.x.push_back(r * std::cos(a));
    c.y.push_back(r * std::sin(a));
    c.z.push_back(-1.2f + (u(rng) < 0.3f ? off(rng) : 0.01f * off(rng)));
    if (u(rng) < 0.02f) c.x.back() = std::numeric_limits<float>::quiet_NaN();
  }
  // Points exactly on sector edges and axes, and at the band edges.
  for (const float a : {0.f, float(M_PI / 2), float(M_PI), float(-M_PI / 2), float(M_PI / 12), float(M_PI / 4)})
    for (const float r : {6.f, 9.f, 14.f, 3.f}) {
      c.x.push_back(r * std::cos(a));
      c.y.push_back(r * std::sin(a));
      c.z.push_back(-1.2f);
      ++c.n;
    }
  while (c.x.size() % 4) {
    c.x.push_back(std::numeric_limits<float>::quiet_NaN());
    c.y.push_back(std::numeric_limits<float>::quiet_NaN());
    c.z.push_back(std::numeric_limits<float>::quiet_NaN());
  }
  return c;
}

struct Result {
  std::vector<int32_t> index;
  std::vector<int16_t> cell;
  std::array<int32_t, kink::kCells> count{};
};

Result run(const Cloud& c) {
  Result r;
  r.index.resize((c.n + 7) & ~size_t(7));
  r.cell.resize(r.index.size());
  const size_t m = kink::cells(c.x.data(), c.y.data(), c.z.data(), c.n, Eigen::Vector3f(0, 0, 1), 1.2f, r.index.data(),
                               r.cell.data(), r.count);
  r.index.resize(m);
  r.cell.resize(m);
  return r;
}

}  // namespace

TEST(KinkCells, EightLanesGiveTheFourLanesCells) {
  if (!kink::wide_available() || !kern::wide()) GTEST_SKIP() << "no eight-lane loop here (not x86-64 with AVX2, or FPLOC_SIMD=sse2)";
  for (const size_t n : {size_t(0), size_t(1), size_t(7), size_t(12), size_t(5001)}) {
    const Cloud c = floor_points(n, unsigned(n + 1));
    kink::set_wide_enabled(false);
    const Result four = run(c);
    kink::set_wide_enabled(true);
    const Result eight = run(c);
    EXPECT_EQ(four.index, eight.index) << n;
    EXPECT_EQ(four.cell, eight.cell) << n;
    EXPECT_EQ(four.count, eight.count) << n;
  }
}

TEST(KinkCells, AzimuthAndDistanceDecideTheCell) {
  const Cloud c = floor_points(4000, 7);
  for (const bool wide : {false, true}) {
    kink::set_wide_enabled(wide);
    const Result r = run(c);
    ASSERT_GT(r.index.size(), 2000u);
    std::array<int32_t, kink::kCells> count{};
    size_t k = 0;
    for (size_t i = 0; i < c.n; ++i) {
      const bool near = std::abs(c.z[i] + 1.2f) <= kink::kSectorBandM;  // (false for NaN)
      const bool kept = k < r.index.size() && size_t(r.index[k]) == i;
      ASSERT_EQ(near && std::isfinite(c.x[i]), kept) << i;
      if (!kept) continue;
      const int cell = r.cell[k++];
      ++count[size_t(cell)];
      const double a = std::atan2(double(c.y[i]), double(c.x[i])) + M_PI;
      const double s = a / (2 * M_PI) * kink::kAzimuths;
      const double h = std::hypot(double(c.x[i]), double(c.y[i]));
      const bool on_edge = std::abs(s - std::round(s)) < 1e-4 ||
                           std::any_of(kink::kBandEdgesM.begin(), kink::kBandEdgesM.end(),
                                       [&](float e) { return std::abs(h - e) < 1e-4; });
      if (on_edge) continue;
      const int band = int(std::upper_bound(kink::kBandEdgesM.begin(), kink::kBandEdgesM.end(), float(h)) -
                           kink::kBandEdgesM.begin());
      EXPECT_EQ(cell, band * kink::kAzimuths + (int(std::floor(s)) % kink::kAzimuths)) << i << " wide " << wide;
    }
    EXPECT_EQ(count, r.count);
  }
  kink::set_wide_enabled(true);
}

TEST(KinkCells, NearPlaneEightLanesKeepTheSamePoints) {
  if (!kink::wide_available() || !kern::wide()) GTEST_SKIP() << "no eight-lane loop here (not x86-64 with AVX2, or FPLOC_SIMD=sse2)";
  // Points around a tilted plane, some exactly at the cut-off (as float), some NaN; blocks of a multiple of 8 as
  // the grouped cells are, the tail of each padded with far points.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-3.f, 3.f), off(-0.08f, 0.08f);
  const Eigen::Vector3f nrm = Eigen::Vector3f(0.05f, -0.03f, 1.f).normalized();
  const float d = 0.02f, cut = 0.05f;
  for (const size_t n : {size_t(0), size_t(5), size_t(8), size_t(13), size_t(3001)}) {
    const size_t np = (n + 7) & ~size_t(7);
    std::vector<float> x(np, 0.f), y(np, 0.f), z(np, 1e3f);
    for (size_t i = 0; i < n; ++i) {
      x[i] = u(rng);
      y[i] = u(rng);
      const float h = i % 17 == 0 ? cut : i % 19 == 0 ? -cut : off(rng);
      z[i] = (h - d - nrm.x() * x[i] - nrm.y() * y[i]) / nrm.z();
      if (i % 23 == 0) y[i] = std::numeric_limits<float>::quiet_NaN();
    }
    std::vector<float> a(np + 16), b(np + 16), c(np + 16), a8(np + 16), b8(np + 16), c8(np + 16);
    kink::set_wide_enabled(false);
    const size_t m4 = kink::near_plane(x.data(), y.data(), z.data(), n, nrm, d, cut, a.data(), b.data(), c.data(), 3);
    kink::set_wide_enabled(true);
    const size_t m8 = kink::near_plane(x.data(), y.data(), z.data(), n, nrm, d, cut, a8.data(), b8.data(), c8.data(), 3);
    ASSERT_EQ(m4, m8) << n;
    for (size_t k = 3; k < m4; ++k) {
      EXPECT_EQ(a[k], a8[k]) << n << " " << k;
      EXPECT_EQ(b[k], b8[k]) << n << " " << k;
      EXPECT_EQ(c[k], c8[k]) << n << " " << k;
    }
    if (n > 1000) EXPECT_GT(m4, n / 2);
  }
}
