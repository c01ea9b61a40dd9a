// The eight-lane wall selection and compaction loops (src/wall_kernels.h, src/compact_kernels.h) move data and
// run the same float tests as the four-lane loops: the segmenter's whole output is the same bit for bit with
// and without them (synthetic scans with dropouts and noise, as measured and gyro de-skewed).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "../src/compact_kernels.h"
#include "../src/plane_kernels.h"
#include "../src/wall_kernels.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"

using namespace fploc;
using namespace fploc::seg;

namespace {

// Every output of one scan as bytes.
void append(const Segmentation& s, std::vector<uint8_t>& out) {
  auto put = [&](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  put(s.ceiling.coeffs.data(), 4 * sizeof(double));
  put(s.ground.coeffs.data(), 4 * sizeof(double));
  for (const double v : {s.roll, s.pitch, s.z}) put(&v, sizeof v);
  for (const int v : {int(s.status), s.ceiling.inliers, s.ceiling.beyond, s.ground.inliers, s.ground.beyond, int(s.deskewed)})
    put(&v, sizeof v);
  for (const auto* v : {&s.wall.x, &s.wall.y, &s.wall.z, &s.wall.range, &s.wall.t}) put(v->data(), v->size() * sizeof(float));
  for (const auto* v : {&s.wall.ring, &s.wall.column}) put(v->data(), v->size() * sizeof(int16_t));
}

// Five scans of the furnished room from moving poses (2 cm noise, 1 % dropouts); with_gyro: column times over
// a 0.1 s sweep and a 0.4 rad/s roll rate, so the returns are de-skewed.
std::vector<uint8_t> run(bool with_gyro) {
  RingSegmenter sg(SegmenterConfig{});
  const auto room = synth::furnished_room();
  const auto beams = synth::os1_like_beams(64);
  std::vector<uint8_t> out;
  size_t walls = 0;
  int deskewed = 0;
  for (int f = 0; f < 5; ++f) {
    const synth::SensorPose pose{-1.0 + 0.1 * f, 0.5, 1.45, (1.0 - 0.3 * f) * M_PI / 180, -0.8 * M_PI / 180, 0.4 + 0.05 * f};
    auto s = synth::render(room, pose, beams, 1024, 0.02, 0.01, unsigned(3 + f)).scan;
    s.utime = 1000000 + 100000 * int64_t(f);
    if (with_gyro) {
      s.column_utime.resize(size_t(s.width));
      for (int c = 0; c < s.width; ++c) s.column_utime[size_t(c)] = s.utime + int64_t(c) * 100000 / s.width;
      for (int64_t t = s.utime - 20000; t <= s.utime + 120000; t += 1000) sg.add_gyro(Eigen::Vector3d(0.4, 0.1, 0.0), t);
    }
    const auto& r = sg.process(s);
    walls += r.wall.size();
    deskewed += r.deskewed;
    append(r, out);
  }
  EXPECT_GT(walls, 5u * 10000u);
  EXPECT_EQ(deskewed, with_gyro ? 5 : 0);
  return out;
}

}  // namespace

TEST(Lane8Kernels, SegmenterOutputIsTheSameWithAndWithoutThem) {
  if (!wallk::available() || !ck::available() || !kern::wide())
    GTEST_SKIP() << "no eight-lane loops here (not x86-64 with AVX2, or FPLOC_SIMD=sse2)";
  for (const bool gyro : {false, true}) {
    wallk::set_enabled(false);
    ck::set_enabled(false);
    const std::vector<uint8_t> four = run(gyro);
    wallk::set_enabled(true);
    ck::set_enabled(true);
    const std::vector<uint8_t> eight = run(gyro);
    ASSERT_EQ(four.size(), eight.size()) << "gyro " << gyro;
    EXPECT_TRUE(std::memcmp(four.data(), eight.data(), four.size()) == 0) << "gyro " << gyro;
  }
}

// A de-skewed scan's wall points on a row whose z is one value: copy8 computes the measured z again from the
// candidate's range [m] (fr * 1e-3f) as zrow[0] fr + zrow[1], fr taken back as round(range * 1000): the same
// floats as the preparation's zrow[0] fr + zrow[1], for every range in mm below kExactRangeMm.
TEST(Lane8Kernels, WallZFromTheCandidateRangeIsTheMeasuredZ) {
  if (!wallk::available() || !kern::wide()) GTEST_SKIP() << "no eight-lane loops here (not x86-64 with AVX2, or FPLOC_SIMD=sse2)";
  const float zrow[2] = {-0.0571263f, 0.0363f};  // (an OS-1 beam's z direction per mm and offset [m])
  constexpr int32_t kChunk = 1 << 16;
  std::vector<float> x(kChunk + 8, 1.f), y(kChunk + 8, 2.f), z(kChunk + 8, 3.f), range(kChunk + 8), col_dt(kChunk, 0.f);
  std::vector<int32_t> pixel(kChunk + 8);
  std::vector<uint8_t> masks(kChunk / 8);
  std::vector<float> ox(kChunk + 8), oy(kChunk + 8), oz(kChunk + 8), orng(kChunk + 8), ot(kChunk + 8);
  std::vector<int16_t> oring(kChunk + 8), ocol(kChunk + 8);
  const wallk::Out out{ox.data(), oy.data(), oz.data(), orng.data(), ot.data(), oring.data(), ocol.data()};
  size_t differ = 0, checked = 0;
  for (uint32_t first = 1; first < wallk::kExactRangeMm; first += kChunk) {
    for (int32_t j = 0; j < kChunk + 8; ++j) {
      range[size_t(j)] = float(first + uint32_t(j)) * 1e-3f;  // (as the preparation stores it)
      pixel[size_t(j)] = j;
    }
    // Full groups, and every eighth group with lanes left out (the compressing path).
    for (int32_t g = 0; g < kChunk / 8; ++g) masks[size_t(g)] = g % 8 == 3 ? uint8_t(0xb5) : uint8_t(0xff);
    const wallk::Source src{x.data(), y.data(), z.data(), range.data(), pixel.data(), zrow};
    const size_t n = wallk::copy8(src, 0, kChunk, 0, 0, 0, masks.data(), col_dt.data(), nullptr, out, 0);
    size_t o = 0;
    for (int32_t g = 0; g < kChunk / 8; ++g)
      for (int l = 0; l < 8; ++l) {
        if (!((masks[size_t(g)] >> l) & 1)) continue;
        const uint32_t mm = first + uint32_t(g * 8 + l);
        const float want = zrow[0] * float(mm) + zrow[1];
        if (mm < wallk::kExactRangeMm) {
          differ += std::memcmp(&want, &oz[o], sizeof want) != 0;
          ++checked;
        }
        ++o;
      }
    EXPECT_EQ(o, n);
  }
  EXPECT_GT(checked, size_t(1800000));
  EXPECT_EQ(differ, 0u);
}
