// refine_map_poses: scans of a synthetic building taken at known poses, given to it at those poses plus the kind of
// per-pose noise the Radish references carry (4 cm, 0.5 deg): the refined poses lie nearer the true ones, and the
// raster of the scans' hits at the refined poses is sharper (fewer occupied cells for the same walls).
#include "fploc/laser2d/map_refine.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace fploc::laser2d {
namespace {

struct Seg {
  Eigen::Vector2d a, b;
};

// A 12 x 8 m floor with a corridor wall, two rooms' walls and a pillar (boxes of walls: enough structure to fix
// every direction from most poses, as an office's rooms do).
std::vector<Seg> building() {
  auto s = [](double ax, double ay, double bx, double by) { return Seg{{ax, ay}, {bx, by}}; };
  return {s(0, 0, 12, 0),   s(12, 0, 12, 8),  s(12, 8, 0, 8),   s(0, 8, 0, 0),   // outer walls
          s(0, 3, 5, 3),    s(6.5, 3, 12, 3),                                    // corridor wall with a door
          s(4, 3, 4, 0.8),  s(8, 3, 8, 1.5),                                     // rooms' walls
          s(3, 5.5, 3.6, 5.5), s(3.6, 5.5, 3.6, 6.1), s(3.6, 6.1, 3, 6.1), s(3, 6.1, 3, 5.5),  // a pillar
          s(9, 6, 11, 7)};                                                        // a slanted cabinet
}

double cast(const std::vector<Seg>& walls, const Eigen::Vector2d& o, double a) {
  const Eigen::Vector2d d(std::cos(a), std::sin(a));
  double best = std::numeric_limits<double>::infinity();
  for (const auto& w : walls) {
    const Eigen::Vector2d e = w.b - w.a;
    const double den = d.x() * e.y() - d.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const Eigen::Vector2d q = w.a - o;
    const double t = (q.x() * e.y() - q.y() * e.x()) / den, u = (q.x() * d.y() - q.y() * d.x()) / den;
    if (t > 0.05 && u >= 0 && u <= 1) best = std::min(best, t);
  }
  return best;
}

// Scans (180 beams over 180 degrees, 5 mm range noise) from a path through the corridor and into the rooms.
void simulate(std::vector<std::vector<Eigen::Vector2d>>* scans, std::vector<Pose2>* truth) {
  const auto walls = building();
  std::mt19937 rng(7);
  std::normal_distribution<double> rn(0, 0.005);
  std::vector<Pose2> path;
  for (int k = 0; k < 40; ++k) path.push_back({0.8 + 0.26 * k, 5.5 + 0.4 * std::sin(0.3 * k), 0.2 * std::sin(0.2 * k)});
  for (int k = 0; k < 20; ++k) path.push_back({10.5 - 0.15 * k, 1.5 + 0.02 * k, M_PI + 0.5 * std::sin(0.4 * k)});
  for (int k = 0; k < 20; ++k) path.push_back({5.8 - 0.12 * k, 4.5 - 0.08 * k, -M_PI / 2 + 0.6 * std::cos(0.3 * k)});
  for (const auto& p : path) {
    std::vector<Eigen::Vector2d> pts;
    for (int i = 0; i < 180; ++i) {
      const double b = -M_PI / 2 + i * M_PI / 180;
      const double r = cast(walls, {p.x, p.y}, p.yaw + b);
      if (!std::isfinite(r) || r > 30) continue;
      const double rr = r + rn(rng);
      pts.push_back({rr * std::cos(b), rr * std::sin(b)});
    }
    scans->push_back(pts);
    truth->push_back(p);
  }
}

std::vector<Pose2> noisy(const std::vector<Pose2>& truth, double sxy, double syaw, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> nx(0, sxy), ny(0, syaw);
  std::vector<Pose2> out;
  for (const auto& p : truth) out.push_back({p.x + nx(rng), p.y + nx(rng), p.yaw + ny(rng)});
  return out;
}

double rms_error(const std::vector<Pose2>& a, const std::vector<Pose2>& b) {
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += std::pow(a[k].x - b[k].x, 2) + std::pow(a[k].y - b[k].y, 2);
  return std::sqrt(s / double(a.size()));
}

// Occupied cells of a 5 cm raster of every hit at the given poses (the bench map's rule with one hit per cell; the
// raster offset so that the building's walls, at multiples of 5 cm, do not lie on cell boundaries).
size_t occupied_cells(const std::vector<std::vector<Eigen::Vector2d>>& scans, const std::vector<Pose2>& poses) {
  std::set<std::pair<int, int>> cells;
  for (size_t k = 0; k < scans.size(); ++k) {
    const double c = std::cos(poses[k].yaw), s = std::sin(poses[k].yaw);
    for (const auto& p : scans[k])
      cells.insert({int(std::floor((poses[k].x + c * p.x() - s * p.y() + 0.0123) / 0.05)),
                    int(std::floor((poses[k].y + s * p.x() + c * p.y() + 0.0123) / 0.05))});
  }
  return cells.size();
}

// The simulated scans, their true poses and reference poses with 4 cm / 0.5 deg of white noise.
struct NoisyScene {
  NoisyScene() {
    simulate(&scans, &truth);
    ref = noisy(truth, 0.04, 0.5 * M_PI / 180, 11);
  }
  std::vector<std::vector<Eigen::Vector2d>> scans;
  std::vector<Pose2> truth, ref;
};

TEST(MapRefine, NoisyReferencePosesComeNearerTheTruthAndTheMapSharper) {
  const NoisyScene sc;
  const auto& [scans, truth, ref] = sc;
  MapRefineStats st;
  const std::vector<Pose2> out = refine_map_poses(scans, ref, {}, &st);
  const double before = rms_error(ref, truth), after = rms_error(out, truth);
  const size_t cells_truth = occupied_cells(scans, truth), cells_before = occupied_cells(scans, ref),
               cells_after = occupied_cells(scans, out);
  ASSERT_EQ(out.size(), ref.size());
  ASSERT_EQ(st.passes.size(), 3u);
  RecordProperty("rms_before_mm", int(before * 1000));
  RecordProperty("rms_after_mm", int(after * 1000));
  std::printf("pose error rms %.1f -> %.1f mm; occupied cells truth %zu, reference %zu, refined %zu; refined %d kept %d\n",
              before * 1e3, after * 1e3, cells_truth, cells_before, cells_after, st.passes.back().refined,
              st.passes.back().kept);
  // Less than half the reference's error (4 cm per axis, 5.7 cm horizontal) is left.
  EXPECT_LT(after, 0.5 * before);
  // The walls are thinner: most of the cells the noise added are gone.
  EXPECT_LT(double(cells_after), double(cells_truth) + 0.5 * double(cells_before - cells_truth));
  // The distance-field variant (the grid localizer's fit on a raster of the others' hits) for comparison: the
  // raster's band is flat, so it removes less of the noise than the lines do.
  MapRefineConfig fc;
  fc.method = MapRefineMethod::kField;
  const double after_field = rms_error(refine_map_poses(scans, ref, fc), truth);
  std::printf("field variant: pose error rms %.1f mm\n", after_field * 1e3);
  EXPECT_LT(after_field, before);
}

// With the high-pass (the corrections' moving mean over +-5 scans removed after each pass) the white noise is still
// mostly removed: the part of the correction it takes out is the slow one, which white noise hardly has.
TEST(MapRefine, HighPassStillRemovesWhiteNoise) {
  const NoisyScene sc;
  const auto& [scans, truth, ref] = sc;
  MapRefineConfig hp;
  hp.highpass_scans = 5;
  const std::vector<Pose2> plain = refine_map_poses(scans, ref), filtered = refine_map_poses(scans, ref, hp);
  const double before = rms_error(ref, truth), after = rms_error(filtered, truth);
  std::printf("high-pass: pose error rms %.1f -> %.1f mm (without it %.1f)\n", before * 1e3, after * 1e3,
              rms_error(plain, truth) * 1e3);
  EXPECT_LT(after, 0.6 * before);
  EXPECT_GT(rms_error(filtered, plain), 0.001);  // the filter changed the poses
}

TEST(MapRefine, ExactPosesStayAndNothingIsRefinedWithoutPasses) {
  std::vector<std::vector<Eigen::Vector2d>> scans;
  std::vector<Pose2> truth;
  simulate(&scans, &truth);
  const std::vector<Pose2> out = refine_map_poses(scans, truth);
  EXPECT_LT(rms_error(out, truth), 0.005);  // the 5 mm range noise moves them by millimetres at most
  MapRefineConfig none;
  none.passes = 0;
  const std::vector<Pose2> ref = noisy(truth, 0.04, 0.5 * M_PI / 180, 3);
  EXPECT_EQ(rms_error(refine_map_poses(scans, ref, none), ref), 0.0);
}

// The map stays in the reference's frame: a common offset of every pose (a frame the scans alone cannot see) is
// held by the prior, not removed.
TEST(MapRefine, ACommonOffsetOfEveryPoseIsKept) {
  std::vector<std::vector<Eigen::Vector2d>> scans;
  std::vector<Pose2> truth;
  simulate(&scans, &truth);
  std::vector<Pose2> shifted = truth;
  for (auto& p : shifted) p.x += 0.3, p.y -= 0.2;
  const std::vector<Pose2> out = refine_map_poses(scans, shifted);
  EXPECT_LT(rms_error(out, shifted), 0.005);
}

}  // namespace
}  // namespace fploc::laser2d
