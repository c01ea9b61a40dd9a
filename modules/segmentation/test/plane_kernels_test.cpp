// The plane fit's point loops (src/plane_kernels.h) against plain scalar loops over the same points: the
// residuals' median bin exactly, the sums to float accuracy; the four-lane and (on AVX2 CPUs) the eight-lane
// versions, with point counts that leave a partial group of four at the end of the eight-lane loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "../src/compact_kernels.h"
#include "../src/plane_kernels.h"
#include "../src/plane_math.h"
#include "../src/seed_order.h"
#include "fploc/segmentation/candidates.h"

using namespace fploc::seg;

namespace {

struct Cloud {
  std::vector<float> x, y, z;
  size_t np = 0;
};

// n points near the plane z = 2.5 (noise 2 cm) plus 30 % scattered within 0.4 m, padded to a multiple of 4
// with `pad` (NaN or a far point).
Cloud make_cloud(size_t n, float pad, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-8.f, 8.f), off(-0.4f, 0.4f);
  std::normal_distribution<float> noise(0.f, 0.02f);
  Cloud c;
  for (size_t i = 0; i < n; ++i) {
    c.x.push_back(u(rng));
    c.y.push_back(u(rng));
    c.z.push_back(2.5f + (i % 10 < 3 ? off(rng) : noise(rng)));
  }
  c.np = (n + 3) & ~size_t(3);
  for (size_t i = n; i < c.np; ++i) {
    c.x.push_back(pad);
    c.y.push_back(pad);
    c.z.push_back(pad);
  }
  return c;
}

const kern::PlaneF kPlane{0.01f, -0.02f, -0.9997499f, 2.5f};  // n.p + d, roughly the ceiling at z = 2.5

float residual(const Cloud& c, size_t i) { return kPlane.nx * c.x[i] + kPlane.ny * c.y[i] + kPlane.nz * c.z[i] + kPlane.d; }

class PlaneKernels : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    kern::set_wide(GetParam());
    if (GetParam() && !kern::wide()) GTEST_SKIP() << "no AVX2/FMA on this CPU (or FPLOC_SIMD=sse2)";
  }
  void TearDown() override { kern::set_wide(true); }
};

TEST_P(PlaneKernels, MedianBinIsTheHistogramsMedianBin) {
  for (size_t n : {5u, 12u, 1001u, 4099u}) {
    const Cloud c = make_cloud(n, 1e3f, unsigned(n));
    for (float cut : {0.2f, 0.05f, 0.013f}) {
      const float inv_bin = float(fploc::seg::k::kScaleBins) / cut;
      // Reference: the 256-bin histogram of |r| < cut and its median bin. Residuals in the same float
      // arithmetic as the kernels' four-lane version (the eight-lane one fuses multiply-adds: a residual on
      // a bin edge may move by one bin, which the tolerance below allows in the median).
      std::vector<int> hist(fploc::seg::k::kScaleBins, 0);
      int inside = 0;
      for (size_t i = 0; i < n; ++i) {
        const float a = std::abs(residual(c, i));
        if (!(a < cut)) continue;
        ++inside;
        ++hist[std::min(int(a * inv_bin), fploc::seg::k::kScaleBins - 1)];
      }
      int acc = 0, bin = 0;
      for (; bin < fploc::seg::k::kScaleBins; ++bin) {
        acc += hist[size_t(bin)];
        if (2 * acc >= inside) break;
      }
      std::vector<float> scratch(c.np);
      int got_inside = -1;
      const int got = kern::residual_scale(c.x.data(), c.y.data(), c.z.data(), c.np, kPlane, inv_bin, cut, scratch.data(), got_inside);
      if (!GetParam()) {
        EXPECT_EQ(got_inside, inside) << n << " " << cut;
        EXPECT_EQ(got, bin) << n << " " << cut;
      } else {
        EXPECT_NEAR(got_inside, inside, 2) << n << " " << cut;
        EXPECT_NEAR(got, bin, 1) << n << " " << cut;
      }
      // A guess of the bin (the last IRLS iteration's scale) changes only the search, never the bin.
      for (int hint : {0, 1, got - 3, got - 1, got, got + 1, got + 2, got + 40, 254, 255, 300}) {
        int hinted_inside = -1;
        EXPECT_EQ(kern::residual_scale(c.x.data(), c.y.data(), c.z.data(), c.np, kPlane, inv_bin, cut, scratch.data(),
                                       hinted_inside, std::max(0, hint)),
                  got)
            << n << " " << cut << " hint " << hint;
      }
    }
  }
}

TEST_P(PlaneKernels, TukeyMomentsMatchScalarSums) {
  for (size_t n : {7u, 260u, 3001u}) {
    const Cloud c = make_cloud(n, 1e3f, unsigned(n) + 1);
    const double cut = 0.1, inv_c2 = 1.0 / (cut * cut);
    double ref[10] = {0};
    for (size_t i = 0; i < n; ++i) {
      const double r = residual(c, i), t = r * r * inv_c2;
      if (t >= 1) continue;
      const double w = (1 - t) * (1 - t), x = c.x[i], y = c.y[i], z = c.z[i];
      const double v[10] = {w, w * x, w * y, w * z, w * x * x, w * x * y, w * x * z, w * y * y, w * y * z, w * z * z};
      for (int q = 0; q < 10; ++q) ref[q] += v[q];
    }
    double S[10];
    kern::tukey_moments(c.x.data(), c.y.data(), c.z.data(), c.np, kPlane, float(inv_c2), S);
    ASSERT_GT(ref[0], 0.5);
    for (int q = 0; q < 10; ++q) EXPECT_NEAR(S[q], ref[q], 1e-4 * (std::abs(ref[q]) + ref[0] * 64)) << n << " moment " << q;
  }
}

TEST_P(PlaneKernels, SoftScoreAndInlierMomentsMatchScalarSums) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t n : {9u, 1003u}) {
    const Cloud c = make_cloud(n, nan, unsigned(n) + 2);  // NaN padding (the candidates' convention)
    const float band = 0.05f, beyond = -0.1f, thr = 0.05f;
    double soft_ref = 0;
    int beyond_ref = 0, cnt_ref = 0;
    double r2_ref = 0, sx_ref = 0, szz_ref = 0;
    const float ref3[3] = {c.x[0], c.y[0], c.z[0]};
    for (size_t i = 0; i < n; ++i) {
      const float r = residual(c, i);
      soft_ref += std::max(0.f, 1 - r * r / (band * band));
      beyond_ref += r < beyond;
      if (std::abs(r) < thr) {
        ++cnt_ref;
        r2_ref += double(r) * r;
        sx_ref += c.x[i] - ref3[0];
        szz_ref += double(c.z[i] - ref3[2]) * (c.z[i] - ref3[2]);
      }
    }
    float soft = 0;
    int nb = 0;
    kern::soft_score(c.x.data(), c.y.data(), c.z.data(), c.np, kPlane, 1.f / (band * band), beyond, soft, nb);
    EXPECT_NEAR(soft, soft_ref, 1e-4 * n) << n;
    EXPECT_NEAR(nb, beyond_ref, GetParam() ? 1 : 0) << n;
    double S[9], r2 = 0;
    int cnt = 0, nb2 = 0;
    kern::inlier_moments(c.x.data(), c.y.data(), c.z.data(), c.np, kPlane, thr, -beyond, ref3, S, r2, cnt, nb2);
    EXPECT_NEAR(cnt, cnt_ref, GetParam() ? 1 : 0) << n;
    EXPECT_NEAR(nb2, nb, GetParam() ? 1 : 0) << n;
    EXPECT_NEAR(r2, r2_ref, 1e-5 * n) << n;
    EXPECT_NEAR(S[0], sx_ref, 1e-3 * n) << n;
    EXPECT_NEAR(S[8], szz_ref, 1e-3 * n) << n;
  }
}

INSTANTIATE_TEST_SUITE_P(Lanes, PlaneKernels, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "Wide" : "FourLanes"; });

}  // namespace

// The band compaction and the inlier moments skip the blocks whose bounding box (Candidates' boxes) lies wholly
// outside what they look for: the same points and bit-identical sums as without the boxes. Runs of points along
// lines (as rings are: tight boxes) at many heights, and planes tilted through them so that blocks lie inside,
// outside and across the band, with points a hair inside and outside the cut-off.
TEST(PlaneKernels, BoxSkipsChangeNothing) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (size_t n : {size_t(1), size_t(63), size_t(64), size_t(1000), size_t(4101)}) {
    std::vector<float> x, y, z;
    for (size_t i = 0; i < n; ++i) {
      const float t = float(i % 97) * 0.1f, h = float(i / 97) * 0.07f - 1.f;
      x.push_back(3.f * std::cos(t) + 0.01f * u(rng));
      y.push_back(3.f * std::sin(t) + 0.01f * u(rng));
      z.push_back(h + (i % 13 == 0 ? 0.5f * u(rng) : 0.f));
    }
    const size_t np = (n + 3) & ~size_t(3);
    for (size_t i = n; i < np + 8; ++i) {
      x.push_back(std::numeric_limits<float>::quiet_NaN());
      y.push_back(std::numeric_limits<float>::quiet_NaN());
      z.push_back(std::numeric_limits<float>::quiet_NaN());
    }
    const size_t stride = (n + Candidates::kBoxPoints - 1) / Candidates::kBoxPoints;
    std::vector<float> box(6 * stride), box2(6 * stride);
    const float r = ck::boxes_scalar(x.data(), y.data(), z.data(), n, box.data(), stride);
    if (ck::available() && kern::wide()) {
      EXPECT_EQ(ck::boxes(x.data(), y.data(), z.data(), n, box2.data(), stride), r);
      EXPECT_EQ(box2, box);
    }
    for (int k = 0; k < 40; ++k) {
      Eigen::Vector3f nn(0.05f * u(rng), 0.05f * u(rng), 1.f);
      nn.normalize();
      // d such that the plane passes through a point of the cloud, moved by +-cut (within float rounding)
      const size_t i0 = size_t(k * 37) % n;
      const float cut = k % 3 == 0 ? 0.2f : k % 3 == 1 ? 0.05f : 0.013f;
      const float d = -(nn.x() * x[i0] + nn.y() * y[i0] + nn.z() * z[i0]) + (k % 2 ? cut : -cut) * (1.f + 1e-7f * float(k % 5));
      const float pl[4] = {nn.x(), nn.y(), nn.z(), d};
      const ck::BoxRange br(box.data(), stride, r, pl);
      for (bool wide : {false, true}) {
        kern::set_wide(wide);
        double S1[9], S2[9], r21, r22;
        int c1, c2, b1, b2;
        const float ref[3] = {x[0], y[0], z[0]};
        kern::inlier_moments(x.data(), y.data(), z.data(), np, {pl[0], pl[1], pl[2], pl[3]}, cut, 2 * cut, ref, S1, r21, c1, b1);
        kern::inlier_moments(x.data(), y.data(), z.data(), np, {pl[0], pl[1], pl[2], pl[3]}, cut, 2 * cut, ref, S2, r22, c2, b2,
                             n, &br);
        EXPECT_EQ(c1, c2);
        EXPECT_EQ(b1, b2);
        EXPECT_EQ(r21, r22);
        for (int q = 0; q < 9; ++q) EXPECT_EQ(S1[q], S2[q]);
      }
      kern::set_wide(true);
      if (!(ck::available() && kern::wide())) continue;
      std::vector<float> bx1(np + 8), by1(np + 8), bz1(np + 8), bx2(np + 8), by2(np + 8), bz2(np + 8);
      const float ref[3] = {0.f, 0.f, 1.f};
      const size_t m1 = ck::band(x.data(), y.data(), z.data(), n, np, pl, cut, ref, bx1.data(), by1.data(), bz1.data());
      const size_t m2 = ck::band(x.data(), y.data(), z.data(), n, np, pl, cut, ref, bx2.data(), by2.data(), bz2.data(), &br);
      ASSERT_EQ(m1, m2);
      for (size_t j = 0; j < m1; ++j) {
        EXPECT_EQ(bx1[j], bx2[j]);
        EXPECT_EQ(by1[j], by2[j]);
        EXPECT_EQ(bz1[j], bz2[j]);
      }
    }
  }
}

// The seed rings' sector maxima sorted with their ranges beside them (src/seed_order.h) come in the order of their
// indices sorted by a look-up of the ranges: the same order, ties included. Ranges in whole millimetres (as the
// candidates'), few distinct values, so that most lists have ties; lists of 1 to 64 (the sectors of a ring).

TEST(SeedOrder, SortedWithTheirRangesAsTheIndicesByRange) {
  struct Key {
    float range;
    int index;
  };
  std::mt19937 rng(17);
  int with_ties = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + trial % 64;
    std::vector<float> range(size_t(3 * n));
    std::uniform_int_distribution<int> mm(3000, 3000 + (trial % 3 == 0 ? 5 : 2000));
    for (auto& r : range) r = float(mm(rng)) * 1e-3f;
    std::vector<int> idx;
    for (int i = 0; i < n; ++i) idx.push_back(3 * i + int(rng() % 3));  // increasing, as the sectors' maxima
    std::vector<Key> keys;
    for (int i : idx) keys.push_back({range[size_t(i)], i});
    std::sort(idx.begin(), idx.end(), [&](int a, int b) { return range[size_t(a)] > range[size_t(b)]; });
    fploc::seg::seeds::sort_by_range(keys);
    ASSERT_EQ(keys.size(), idx.size());
    for (size_t j = 0; j < idx.size(); ++j) ASSERT_EQ(keys[j].index, idx[j]) << "trial " << trial << " position " << j;
    for (size_t j = 1; j < idx.size(); ++j) with_ties += range[size_t(idx[j])] == range[size_t(idx[j - 1])];
  }
  EXPECT_GT(with_ties, 1000);
}

// Moments::of_points (the ground-at-a-kink's sweep correction) gives the moments of adding the points one at a
// time with add1, bit for bit: points around a floor 1.2 m below, relative to a reference point, as that
// correction forms them.
TEST(PlaneMath, MomentsOfPointsAreThoseAddedOneAtATime) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(-8.f, 8.f), h(-0.05f, 0.05f);
  for (size_t m : {size_t(0), size_t(1), size_t(7), size_t(1000), size_t(25000)}) {
    std::vector<float> x(m), y(m), z(m);
    for (size_t j = 0; j < m; ++j) {
      x[j] = u(rng);
      y[j] = u(rng);
      z[j] = 0.02f * x[j] - 0.01f * y[j] + h(rng);
    }
    fploc::seg::detail::Moments one;
    for (size_t j = 0; j < m; ++j) one.add1(Eigen::Vector3f(x[j], y[j], z[j]).cast<double>());
    const auto all = fploc::seg::detail::Moments::of_points(x.data(), y.data(), z.data(), m);
    EXPECT_EQ(all.w, one.w) << m;
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(all.s[a], one.s[a]) << m << " s" << a;
      for (int b = 0; b < 3; ++b) EXPECT_EQ(all.ss(a, b), one.ss(a, b)) << m << " ss" << a << b;
    }
  }
}
