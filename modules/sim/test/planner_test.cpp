// auto-loop on the demo plans and on real CAD plans; the shipped demo plan files match the code.
#include <gtest/gtest.h>

#include <filesystem>

#include "fploc/floorplan/io.h"
#include "fploc/sim/planner.h"
#include "fploc/sim/scenarios.h"
#include "fploc/sim/simulator.h"

using namespace fploc;
using namespace fploc::sim;

namespace {

void check_loop(const FloorPlan& plan, double min_len) {
  const AutoLoopResult r = plan_auto_loop(plan);
  const Motion m(r.control, true, SpeedSpec{0.55, 0.4}, 0, 0);
  const auto path = m.sample_path(0.02);
  EXPECT_GE(min_clearance(plan, path), 0.4) << plan.source;
  EXPECT_GT(m.length(), min_len) << plan.source;
  EXPECT_LT((path.front() - path.back()).norm(), 1e-6);
  // Smooth: turning radius >= 0.5 m (heading change per 2 cm sample <= 0.04 rad).
  for (size_t i = 2; i < path.size(); ++i) {
    const Eigen::Vector2d a = path[i - 1] - path[i - 2], b = path[i] - path[i - 1];
    if (a.norm() < 1e-3 || b.norm() < 1e-3) continue;
    const double ang = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
    EXPECT_LT(ang, 0.02 / 0.5) << plan.source << " sample " << i;
  }
}

}  // namespace

TEST(AutoLoop, DemoPlans) {
  check_loop(demo_room_plan(), 30);
  check_loop(demo_corridor_plan(), 75);  // the corridor ring (~84 m), not the enclosed inner block (~65 m)
}

TEST(AutoLoop, SharedCadPlans) {
  const std::string dir = std::string(FPLOC_SHARED_DIR) + "/data/floorplans/";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "no ../shared/data";
  struct P {
    const char* file;
    std::vector<std::string> layers;
  };
  const P plans[] = {{"shanghaitech_SIST-F4-filtered.dxf", {"*WALL*", "*COLS*"}},
                     {"annf-demo-corridor-lines.csv", {}},
                     {"barcelona_pavilion_plan.dxf", {"Walls", "Columns"}}};  // open plan: bounding-box fallback
  int tested = 0;
  for (const auto& p : plans) {
    FloorPlan plan;
    try {
      plan = load_floor_plan(dir + p.file, p.layers, p.file[0] == 'a' ? "cm" : "");
    } catch (const std::exception& e) {
      std::cerr << "skipping " << p.file << ": " << e.what() << "\n";
      continue;
    }
    check_loop(plan, 10);
    ++tested;
  }
  if (tested == 0) GTEST_SKIP() << "no shared plan could be loaded";
}

TEST(AutoLoop, SimulatorRunsOnAnyPlan) {
  SimulatorOptions o;
  o.scenario = "auto-loop-fast";
  Simulator sim(demo_corridor_plan(), o);
  EXPECT_GT(sim.num_frames(), 100);
  EXPECT_NEAR(sim.motion().avg_speed(), 0.65, 0.03);
}

TEST(AutoLoop, PaperScenarioRefusesAnotherPlan) {
  SimulatorOptions o;
  o.scenario = "room-large-loop-fast";
  EXPECT_THROW(Simulator(demo_corridor_plan(), o), std::runtime_error);
  EXPECT_NO_THROW(Simulator(load_floor_plan(std::string(FPLOC_SOURCE_DIR) + "/data/plans/room.json"), o));
}

TEST(DemoPlans, ShippedFilesMatchCode) {
  for (const auto& [file, plan] : {std::make_pair("room.json", demo_room_plan()), std::make_pair("corridor.json", demo_corridor_plan())}) {
    const std::string path = std::string(FPLOC_SOURCE_DIR) + "/data/plans/" + file;
    const FloorPlan loaded = load_floor_plan(path);
    ASSERT_EQ(loaded.elements.size(), plan.elements.size()) << path;
    for (size_t i = 0; i < plan.elements.size(); ++i) {
      EXPECT_EQ(loaded.elements[i].kind, plan.elements[i].kind);
      EXPECT_LT((loaded.elements[i].a - plan.elements[i].a).norm() + (loaded.elements[i].b - plan.elements[i].b).norm() +
                    (loaded.elements[i].c - plan.elements[i].c).norm() + std::abs(loaded.elements[i].r - plan.elements[i].r),
                1e-9);
    }
  }
  // Paper-like: ~200 m^2 inside the room.
  const Box2 b = demo_room_plan().bounds();
  EXPECT_GT(b.size().x() * b.size().y(), 200.0);
}

// `fploc sim --plan mm.dxf --scenario auto-loop-medium` on a drawing in mm read as metres said only
// "fploc sim: std::bad_alloc" (a 3e10-cell grid); now one error naming the plan, its size and the units.
TEST(AutoLoop, APlanInTheWrongUnitsIsRefused) {
  FloorPlan mm = demo_room_plan();
  scale_plan(mm, 1000);
  mm.source = "room_mm.dxf";
  try {
    (void)plan_auto_loop(mm, AutoLoopConfig{});
    FAIL() << "planned a loop on a 20 km room";
  } catch (const std::exception& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("auto-loop: room_mm.dxf is 20500 x 13000 m, too large to plan a path on"), std::string::npos) << w;
    EXPECT_NE(w.find("check the units"), std::string::npos) << w;
  }
}
