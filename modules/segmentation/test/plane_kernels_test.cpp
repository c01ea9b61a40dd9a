// The plane fit's point loops (src/plane_kernels.h) against plain scalar loops over the same points: the
// residuals' median bin exactly, the sums to float accuracy; the four-lane and (on AVX2 CPUs) the eight-lane
// versions, with point counts that leave a partial group of four at the end of the eight-lane loop.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "../src/plane_kernels.h"

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
