// The diff against a known renovation: scans ray cast (2D, level, at 2.5 m: above the windows' head) in a renovated world
// from poses along the demo room's loop, diffed against the original plan.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "fploc/floorplan/io.h"
#include "fploc/plandiff/plan_diff.h"
#include "fploc/sim/perturb.h"
#include "fploc/sim/scenarios.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using V2 = Eigen::Vector2d;

namespace {

struct DiffRun {
  FloorPlan plan;
  sim::WorldEdit edit;
  plandiff::Diff diff;
};

DiffRun simulate_and_diff(const std::string& family, uint64_t seed) {
  DiffRun r;
  r.plan = sim::demo_room_plan();
  sim::SimulatorOptions so;
  so.scenario = "room-small-loop-medium";
  so.clutter = false;
  sim::Simulator s(FloorPlan{}, so);
  const auto path = s.motion().sample_path(0.1);
  r.edit = sim::perturb_world(r.plan, path, sim::perturb_family(family), seed);
  sim::World world(r.edit.world);
  for (const auto& p : r.edit.people) world.add_person(p);
  plandiff::PlanDiff d(r.plan);
  uint64_t st = seed;
  for (size_t k = 0; k < path.size(); k += 5) {
    const V2 o = path[k];
    const double yaw = 0.3 + 0.01 * double(k);  // any heading: the points are given in the sensor frame
    world.set_time(0.1 * double(k));
    std::vector<Eigen::Vector2f> pts;
    for (int i = 0; i < 720; ++i) {
      st = st * 6364136223846793005ull + 1442695040888963407ull;
      if ((st >> 40) % 3 != 0) continue;  // a sparse subset, as feature points are
      const double a = i * M_PI / 360;
      const Eigen::Vector3d dir(std::cos(a), std::sin(a), 0);
      const sim::Hit h = world.cast(Eigen::Vector3d(o.x(), o.y(), 2.5), dir, 30.0);
      if (!std::isfinite(h.t)) continue;
      const double rel = a - yaw;
      pts.emplace_back(float(h.t * std::cos(rel)), float(h.t * std::sin(rel)));
    }
    d.add_frame(o.x(), o.y(), yaw, pts);
  }
  r.diff = d.result();
  return r;
}

}  // namespace

TEST(PlanDiff, FindsAKnownRenovation) {
  const DiffRun r = simulate_and_diff("renovated", 1);
  int removed_visible = 0, removed_found = 0, moved = 0, moved_found = 0, false_flags = 0;
  for (size_t i = 0; i < r.plan.elements.size(); ++i) {
    const auto& t = r.edit.elements[i];
    const auto& e = r.diff.elements[i];
    const bool flagged = e.status == plandiff::Status::kMissing || e.status == plandiff::Status::kMoved;
    if (t.change == sim::ElementChange::kRemoved && e.frames_expected > 0) {
      ++removed_visible;
      if (e.status == plandiff::Status::kMissing) ++removed_found;
    } else if (t.change == sim::ElementChange::kMoved && e.frames_with_points > 0) {
      ++moved;
      if (e.status == plandiff::Status::kMoved) {
        ++moved_found;
        EXPECT_NEAR(e.offset_m, t.offset_m, 0.03) << "element " << i;
      }
    } else if (t.change == sim::ElementChange::kUnchanged && flagged) {
      ++false_flags;
      ADD_FAILURE() << "element " << i << " flagged " << plandiff::status_name(e.status) << " offset " << e.offset_m;
    }
  }
  EXPECT_GE(removed_visible, 2);
  EXPECT_EQ(removed_found, removed_visible);
  EXPECT_GE(moved, 2);
  EXPECT_EQ(moved_found, moved);
  // Both partitions come back as new walls where they were built.
  ASSERT_EQ(r.edit.added.size(), 2u);
  for (const auto& a : r.edit.added) {
    bool found = false;
    for (const auto& n : r.diff.added) {
      const V2 u = (a.b - a.a).normalized();
      const double off = std::abs(u.x() * (n.a - a.a).y() - u.y() * (n.a - a.a).x());
      const double ang = std::abs(u.x() * (n.b - n.a).normalized().y() - u.y() * (n.b - n.a).normalized().x());
      if (off < 0.1 && ang < 0.1 && n.length() > 0.7 * (a.b - a.a).norm()) found = true;
    }
    EXPECT_TRUE(found) << "partition " << a.a.transpose() << " -> " << a.b.transpose();
  }
  EXPECT_LE(int(r.diff.added.size()), 2 + 1);
}

TEST(PlanDiff, CleanWorldHasNoFlags) {
  const DiffRun r = simulate_and_diff("crowd-15", 2);  // the plan is the world; 15 people walk about
  EXPECT_EQ(r.diff.count(plandiff::Status::kMissing), 0);
  EXPECT_EQ(r.diff.count(plandiff::Status::kMoved), 0);
  EXPECT_TRUE(r.diff.added.empty()) << r.diff.added.size() << " new, first " << r.diff.added[0].a.transpose();
  EXPECT_GT(r.diff.count(plandiff::Status::kSeen), 20);
}

TEST(PlanDiff, DxfHasTheLayersAndLoadsBack) {
  const DiffRun r = simulate_and_diff("renovated", 1);
  std::ostringstream dxf;
  plandiff::write_dxf(r.diff, r.plan, dxf);
  const std::string text = dxf.str();
  for (const char* l : {"FPLOC-MISSING", "FPLOC-MOVED", "FPLOC-NEW", "FPLOC-PLAN"})
    EXPECT_NE(text.find(std::string("LAYER\n2\n") + l), std::string::npos) << l;
  // The project's own DXF reader takes it back: the diff layers alone.
  const std::string path = ::testing::TempDir() + "diff.dxf";
  { std::ofstream(path) << text; }
  const FloorPlan back = load_floor_plan(path, {"FPLOC-MISSING", "FPLOC-MOVED", "FPLOC-NEW"});
  EXPECT_EQ(back.elements.size(), size_t(r.diff.count(plandiff::Status::kMissing) + r.diff.count(plandiff::Status::kMoved)) +
                                      r.diff.added.size());
  std::ostringstream js;
  plandiff::write_json(r.diff, r.plan, js);
  EXPECT_NE(js.str().find("\"missing\""), std::string::npos);
}

TEST(PlanDiff, EstimatesTheDrawingScale) {
  const DiffRun s = simulate_and_diff("scale-0.5pct", 4);  // the building 0.5 % larger than its drawing
  ASSERT_GT(s.diff.scale_points, 1000);
  EXPECT_NEAR(s.diff.scale_error, 0.005, 0.001);
  EXPECT_GT(s.diff.scale_sigma, 0.0);
  EXPECT_LT(s.diff.scale_sigma, 0.002);
  const DiffRun c = simulate_and_diff("crowd-15", 4);  // to scale
  EXPECT_NEAR(c.diff.scale_error, 0.0, 0.001);
}
