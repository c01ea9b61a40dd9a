// The simulator's ceilings against what the segmenter is told about them: a building-* scenario's ceiling
// map written as a building file (`fploc sim --ceilings-building`, sim::ceiling_map_building_text) and read
// back through the loader (load_building) and the segmenter's lookup (AreaCeilingMap + AreaHeights, filled as
// nodes/segmenter does) gives the height the ray caster hits, within 1 mm, wherever a ray reaches the ceiling:
// vertical rays on a grid over the plan and rays from the scenario's path in every upward direction. Hanging
// objects (lamps, beams, ducts, grid T-bars) are not in the file on purpose: rays stopped by them are skipped.
// Also the shipped demo building (overlapping areas, "the first area containing a point wins"): its floors'
// worlds against the building's own lookup.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "fploc/floorplan/building.h"
#include "fploc/floorplan/io.h"
#include "fploc/segmentation/area_ceilings.h"
#include "fploc/sim/building_world.h"
#include "fploc/sim/ceiling_map.h"
#include "fploc/sim/simulator.h"

using namespace fploc;

namespace {

struct CeilingHit {
  Eigen::Vector2d xy;
  double z;  // height above the floor the ray caster hit the ceiling at
};

// The segmenter's map of a building floor, filled as the segmenter node fills it (segmenter_node_impl.h).
seg::AreaCeilingMap segmenter_map(const BuildingFloor& f) {
  seg::AreaCeilingMap map;
  map.floor = f.name;
  map.default_height_m = f.ceiling_height;
  for (const auto& a : f.areas) map.areas.push_back({a.name, a.polygon, a.height, a.origin, a.slope});
  map.finish();
  return map;
}

// The floor under (x, y) in a world (its first ground patch there, else 0).
double floor_at(const sim::World& w, double x, double y) {
  for (const auto& g : w.ground_patches())
    if (sim::polygon_contains(g.polygon, x, y)) return g.height(x, y);
  return 0.0;
}

// Vertical rays on a grid over the world's bounds (offset so no sample lies on a round-numbered edge).
std::vector<CeilingHit> grid_hits(const sim::World& w, double step, int* blocked) {
  std::vector<CeilingHit> out;
  const Box2 b = w.bounds();
  for (double x = b.min.x() + 0.0371; x < b.max.x(); x += step)
    for (double y = b.min.y() + 0.0529; y < b.max.y(); y += step) {
      const double z0 = floor_at(w, x, y) + 0.05;
      const sim::Hit h = w.cast(Eigen::Vector3d(x, y, z0), Eigen::Vector3d::UnitZ(), 100.0);
      if (h.label != sim::Label::kCeiling) {
        ++*blocked;
        continue;
      }
      out.push_back({Eigen::Vector2d(x, y), z0 + h.t});
    }
  return out;
}

// Rays from the sensor along the path, every upward direction (elevation 2..88 deg, 10 deg of azimuth).
std::vector<CeilingHit> path_hits(const sim::World& w, const sim::SensorTrajectory& m, int* blocked) {
  std::vector<CeilingHit> out;
  for (double t = 0; t <= m.duration(); t += 2.0) {
    const Eigen::Vector3d o = m.pose(t).translation();
    for (double el = 2; el < 89; el += 6)
      for (double az = 0; az < 360; az += 10) {
        const double e = el * M_PI / 180, a = az * M_PI / 180;
        const Eigen::Vector3d d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
        const sim::Hit h = w.cast(o, d, 200.0);
        if (h.label == sim::Label::kClutter) ++*blocked;
        if (h.label != sim::Label::kCeiling) continue;
        const Eigen::Vector3d p = o + h.t * d;
        out.push_back({p.head<2>(), p.z()});
      }
  }
  return out;
}

struct Mismatch {
  int n = 0;
  double worst = 0;
  std::string first;
};

// Every hit against the building floor's lookup and the segmenter's.
void compare(const std::vector<CeilingHit>& hits, const BuildingFloor& f, const char* what, Mismatch& mm) {
  const seg::AreaCeilingMap map = segmenter_map(f);
  seg::AreaHeights heights;
  heights.reset(map, 51);
  for (const auto& h : hits) {
    const double loader = f.ceiling_height_at(h.xy);
    const int area = map.area_at(h.xy);
    const double segmenter = heights.height_at(area, h.xy);
    const double err = std::max(std::abs(loader - h.z), std::abs(segmenter - h.z));
    if (err > 1e-3) {
      if (mm.n++ == 0) {
        char buf[300];
        std::snprintf(buf, sizeof buf, "%s at (%.3f, %.3f): ray caster %.4f m, loader %.4f m, segmenter %.4f m (area '%s')",
                      what, h.xy.x(), h.xy.y(), h.z, loader, segmenter, map.name(area).c_str());
        mm.first = buf;
      }
      mm.worst = std::max(mm.worst, err);
    }
  }
}

}  // namespace

TEST(BuildingCeilings, SimulatedCeilingsReadBackAsTheRaysSeeThem) {
  const std::string dir = testing::TempDir();
  for (const std::string plan_name : {"room", "corridor"}) {
    const std::string plan_file = std::string(FPLOC_SOURCE_DIR) + "/data/plans/" + plan_name + ".json";
    const FloorPlan plan = load_floor_plan(plan_file);
    for (const std::string kind : {"areas", "atrium", "clutter", "mixed"}) {
      const std::string scenario = "building-" + kind + "-medium";
      SCOPED_TRACE(plan_name + " : " + scenario);
      sim::SimulatorOptions o;
      o.scenario = scenario;
      o.seed = 1;
      o.shared_dir = FPLOC_SHARED_DIR;
      sim::Simulator s(plan, o);
      const std::string file = dir + "/ceilings_" + plan_name + "_" + kind + ".pbtxt";
      {
        std::ofstream f(file);
        f << sim::ceiling_map_building_text(s.ceiling_map(), plan_file);
        ASSERT_TRUE(f.good());
      }
      const Building b = load_building(file);
      ASSERT_EQ(b.floors.size(), 1u);
      const BuildingFloor& fl = b.floors[0];
      EXPECT_EQ(fl.elevation, 0.0);
      // The plan the file names is the plan the world was built from (same frame, same units).
      const Box2 pb = load_floor_plan(b, fl.name).bounds();
      EXPECT_LT((pb.min - s.world().bounds().min).norm() + (pb.max - s.world().bounds().max).norm(), 1e-9);
      // The plan's layer globs and units override go along (fploc sim --layers/--units).
      const Building bl = parse_building(sim::ceiling_map_building_text(s.ceiling_map(), plan_file, "0", {"walls", "col*"}, "m"), file);
      EXPECT_EQ(bl.floors[0].layers, (std::vector<std::string>{"walls", "col*"}));
      EXPECT_EQ(bl.floors[0].units, "m");
      EXPECT_EQ(bl.floors[0].areas.size(), fl.areas.size());
      int blocked_grid = 0, blocked_path = 0;
      const auto grid = grid_hits(s.world(), 0.25, &blocked_grid);
      const auto path = path_hits(s.world(), s.motion(), &blocked_path);
      const double cells = (s.world().bounds().size().x() / 0.25) * (s.world().bounds().size().y() / 0.25);
      EXPECT_GT(double(grid.size()), 0.8 * cells);
      EXPECT_GT(path.size(), 1000u);
      Mismatch mm;
      compare(grid, fl, "grid", mm);
      compare(path, fl, "path", mm);
      EXPECT_EQ(mm.n, 0) << mm.first << " (" << mm.n << " hits off, worst " << mm.worst << " m)";
      // The simulator's own lookup agrees too (hanging objects hang from it).
      int own = 0;
      for (const auto& h : grid) own += !(std::abs(s.ceiling_map().height_at(h.xy) - h.z) <= 1e-3);
      EXPECT_EQ(own, 0);
      std::printf("%s : %s: %zu grid + %zu path ceiling hits (%d + %d stopped by hanging objects), %zu areas\n",
                  plan_name.c_str(), scenario.c_str(), grid.size(), path.size(), blocked_grid, blocked_path, fl.areas.size());
    }
  }
}

TEST(BuildingCeilings, DemoBuildingFloorsAreWhatTheRaysSee) {
  // Overlapping areas (the ground floor's stairs inside the office's drop ceiling, the lift car inside the
  // lobby): the first area containing a point owns it, in the building and in the simulated world alike.
  const Building b = load_building(std::string(FPLOC_SOURCE_DIR) + "/data/buildings/demo-building.pbtxt");
  for (size_t i = 0; i < b.floors.size(); ++i) {
    SCOPED_TRACE(b.floors[i].name);
    const FloorPlan plan = load_floor_plan(b, b.floors[i].name);
    sim::FloorGround g;
    std::string note;
    const auto w = sim::make_floor_world(b, int(i), plan, sim::FloorWorldOptions{}, &g, &note);
    int blocked = 0;
    const auto grid = grid_hits(*w, 0.25, &blocked);
    EXPECT_GT(grid.size(), 5000u);
    Mismatch mm;
    compare(grid, b.floors[i], "grid", mm);
    EXPECT_EQ(mm.n, 0) << mm.first << " (" << mm.n << " hits off, worst " << mm.worst << " m)";
    int own = 0;
    for (const auto& h : grid) own += !(std::abs(w->ceiling_at(h.xy.x(), h.xy.y()) - h.z) <= 1e-3);
    EXPECT_EQ(own, 0) << "World::ceiling_at against its own rays";
    std::printf("demo building, floor %s: %zu grid ceiling hits, %d rays stopped before the ceiling\n", b.floors[i].name.c_str(),
                grid.size(), blocked);
  }
}
