#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "fploc/features/features.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"

using namespace fploc;
using namespace fploc::feat;
namespace synth = fploc::seg::synth;

namespace {
constexpr double kDeg = M_PI / 180.0;

// Distance of a world xy point to the plan of a synthetic room (walls + pillar boxes), and which element.
double plan_distance(const synth::Room& room, double x, double y, int* element = nullptr) {
  double best = std::abs(std::abs(x) - room.half_x);
  int id = x > 0 ? 0 : 1;
  auto take = [&](double d, int e) {
    if (d < best) {
      best = d;
      id = e;
    }
  };
  take(std::abs(std::abs(y) - room.half_y), y > 0 ? 2 : 3);
  int e = 4;
  for (const auto& b : room.boxes) {
    if (b.label != synth::kWall) continue;
    // Four sides of the box footprint.
    auto seg = [&](double x1, double y1, double x2, double y2) {
      const double dx = x2 - x1, dy = y2 - y1;
      const double t = std::clamp(((x - x1) * dx + (y - y1) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
      take(std::hypot(x - x1 - t * dx, y - y1 - t * dy), e++);
    };
    seg(b.lo.x(), b.lo.y(), b.hi.x(), b.lo.y());
    seg(b.hi.x(), b.lo.y(), b.hi.x(), b.hi.y());
    seg(b.hi.x(), b.hi.y(), b.lo.x(), b.hi.y());
    seg(b.lo.x(), b.hi.y(), b.lo.x(), b.lo.y());
  }
  if (element) *element = id;
  return best;
}

struct Run {
  seg::Segmentation seg;
  FeatureFrame f;
};

Run run(const synth::Room& room, const synth::SensorPose& pose, double noise, uint32_t seed) {
  auto s = synth::render(room, pose, synth::os1_like_beams(), 1024, noise, 0.01, seed);
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  Run r;
  r.seg = sg.process(s.scan);
  FeatureExtractor fx;
  r.f = fx.process(r.seg);
  return r;
}
}  // namespace

TEST(Features, EmptyRoomSurfacesOnWallsGroupsOnOneWall) {
  synth::Room room;
  synth::SensorPose pose{1.0, -0.5, 1.5, 2 * kDeg, -1.5 * kDeg, 0.4};
  const auto r = run(room, pose, 0.005, 11);
  ASSERT_EQ(r.seg.status, seg::SegStatus::kOk);
  const auto& f = r.f;
  ASSERT_EQ(f.status, FeatureStatus::kOk);
  size_t surf = 0, corner = 0, on_plan = 0;
  std::map<int, std::map<int, int>> group_elements;
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  for (size_t i = 0; i < f.size(); ++i) {
    const double wx = c * f.points[i].p.x() - s * f.points[i].p.y() + pose.x, wy = s * f.points[i].p.x() + c * f.points[i].p.y() + pose.y;
    int el = -1;
    const double d = plan_distance(room, wx, wy, &el);
    if (f.points[i].kind == FeatureKind::kSurface) {
      ++surf;
      on_plan += d < 0.03;  // roll/pitch compensated: a tilt error would smear walls by several cm
      if (f.points[i].group >= 0) group_elements[f.points[i].group][el]++;
    } else {
      ++corner;
      EXPECT_EQ(f.points[i].group, -1);
    }
  }
  EXPECT_GT(surf, 1000u);
  EXPECT_GT(corner, 10u);
  EXPECT_GE(double(on_plan) / surf, 0.99);
  // Groups: every group's points lie on one wall.
  ASSERT_GT(f.num_groups, 20);
  int pure = 0;
  for (auto& [g, els] : group_elements) {
    int total = 0, top = 0;
    for (auto& [e, n] : els) {
      total += n;
      top = std::max(top, n);
    }
    pure += top == total;
  }
  EXPECT_GE(double(pure) / group_elements.size(), 0.95);
}

TEST(Features, CornersAtRoomAndPillarCorners) {
  synth::Room room = synth::furnished_room();
  room.boxes.erase(room.boxes.begin() + 2, room.boxes.end());  // pillars only
  synth::SensorPose pose{0.0, 0.0, 1.5, 0, 0, 0};
  const auto r = run(room, pose, 0.003, 12);
  // Every corner feature is near a vertical edge of the plan (room corners, pillar corners) or a place
  // where one element occludes another.
  std::vector<Eigen::Vector2d> edges = {{8, 6}, {-8, 6}, {8, -6}, {-8, -6}};
  for (const auto& b : room.boxes)
    for (double x : {b.lo.x(), b.hi.x()})
      for (double y : {b.lo.y(), b.hi.y()}) edges.emplace_back(x, y);
  int corners = 0, near_edge = 0;
  for (size_t i = 0; i < r.f.size(); ++i) {
    if (r.f.points[i].kind != FeatureKind::kCorner) continue;
    ++corners;
    double best = 1e9;
    for (const auto& e : edges) best = std::min(best, std::hypot(r.f.points[i].p.x() - e.x(), r.f.points[i].p.y() - e.y()));
    near_edge += best < 0.3;
  }
  ASSERT_GT(corners, 10);
  EXPECT_GE(double(near_edge) / corners, 0.9);
}

TEST(Features, BadAndEmptyInput) {
  FeatureExtractor fx;
  seg::Segmentation s;
  s.status = seg::SegStatus::kOk;  // segmented, but no wall points
  EXPECT_EQ(fx.process(s).status, FeatureStatus::kFewFeatures);
  s.status = seg::SegStatus::kNoCeiling;
  EXPECT_EQ(fx.process(s).status, FeatureStatus::kFewFeatures);
  // An unusable scan upstream is passed on.
  s.status = seg::SegStatus::kEmpty;
  EXPECT_EQ(fx.process(s).status, FeatureStatus::kBadInput);
  s.status = seg::SegStatus::kBadInput;
  EXPECT_EQ(fx.process(s).status, FeatureStatus::kBadInput);
  s.status = seg::SegStatus::kOk;
  s.wall.x.push_back(1.f);
  EXPECT_EQ(fx.process(s).status, FeatureStatus::kBadInput);
  s.wall.clear();
  s.roll = std::nan("");
  EXPECT_EQ(fx.process(s).status, FeatureStatus::kBadInput);
}
