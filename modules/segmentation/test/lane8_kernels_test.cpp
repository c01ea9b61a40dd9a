// The eight-lane wall selection and compaction loops (src/wall_kernels.h, src/compact_kernels.h) move data and
// run the same float tests as the four-lane loops: the segmenter's whole output is the same bit for bit with
// and without them (synthetic scans with dropouts and noise, as measured and gyro de-skewed).
#include <gtest/gtest.h>

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
