// World != plan: perturbations are deterministic per seed, their truth matches the world they build,
// and world files that do not parse give one clear error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "fploc/sim/perturb.h"
#include "fploc/sim/scenarios.h"
#include "fploc/sim/simulator.h"
#include "fploc/sim/world.h"

using namespace fploc;
using namespace fploc::sim;
using V2 = Eigen::Vector2d;

namespace {

std::vector<V2> room_path() {
  SimulatorOptions o;
  o.scenario = "room-small-loop-medium";
  o.clutter = false;
  o.shared_dir = "";
  Simulator sim(FloorPlan{}, o);
  return sim.motion().sample_path(0.1);
}

std::string tmp_file(const std::string& name, const std::string& text) {
  const std::string p = ::testing::TempDir() + name;
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST(Perturb, DeterministicBySeed) {
  const FloorPlan plan = demo_room_plan();
  const auto path = room_path();
  const PerturbOptions o = perturb_family("mixed");
  const WorldEdit a = perturb_world(plan, path, o, 7), b = perturb_world(plan, path, o, 7), c = perturb_world(plan, path, o, 8);
  EXPECT_EQ(a.truth_json(plan), b.truth_json(plan));
  ASSERT_EQ(a.world.elements.size(), b.world.elements.size());
  for (size_t i = 0; i < a.world.elements.size(); ++i) {
    EXPECT_EQ(a.world.elements[i].a, b.world.elements[i].a);
    EXPECT_EQ(a.world.elements[i].b, b.world.elements[i].b);
  }
  ASSERT_EQ(a.people.size(), b.people.size());
  for (size_t i = 0; i < a.people.size(); ++i) EXPECT_EQ(a.people[i].path[0], b.people[i].path[0]);
  EXPECT_NE(a.truth_json(plan), c.truth_json(plan));
}

TEST(Perturb, AsBuiltSigmaAndScale) {
  const FloorPlan plan = demo_room_plan();
  const auto path = room_path();
  const WorldEdit w = perturb_world(plan, path, parse_perturb("asbuilt=0.05"), 3);
  ASSERT_EQ(w.world.elements.size(), plan.elements.size());
  double s2 = 0;
  int n = 0;
  for (const auto& t : w.elements) {
    EXPECT_EQ(t.change, ElementChange::kUnchanged);
    s2 += t.offset_m * t.offset_m;
    ++n;
  }
  const double rms = std::sqrt(s2 / n);
  EXPECT_GT(rms, 0.02);  // the mean of two N(0, 0.05) ends along the normal: sigma 0.035
  EXPECT_LT(rms, 0.07);
  // Walls stay joined: a shared end moves the same way in both walls.
  EXPECT_EQ(w.world.elements[0].b, w.world.elements[1].a);

  const WorldEdit s = perturb_world(plan, path, parse_perturb("scale=0.01"), 3);
  const Box2 pb = plan.bounds(), wb = s.world.bounds();
  EXPECT_NEAR(wb.size().x() / pb.size().x(), 1.01, 1e-9);
  EXPECT_NEAR(wb.size().y() / pb.size().y(), 1.01, 1e-9);
}

TEST(Perturb, RenovationTruthMatchesTheWorld) {
  const FloorPlan plan = demo_room_plan();
  const auto path = room_path();
  const WorldEdit w = perturb_world(plan, path, perturb_family("renovated"), 1);
  int removed = 0, moved = 0, kept = 0;
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    const auto& t = w.elements[i];
    if (t.change == ElementChange::kRemoved) ++removed;
    if (t.change == ElementChange::kMoved) {
      ++moved;
      EXPECT_GE(std::abs(t.offset_m), 0.1 - 1e-9);
      EXPECT_LE(std::abs(t.offset_m), 0.25 + 1e-9);
    }
    if (t.change == ElementChange::kUnchanged) {
      ++kept;
      EXPECT_EQ(t.max_shift_m, 0.0);
    }
  }
  EXPECT_GE(removed, 2);  // two removals (a wall takes its other face along)
  EXPECT_GE(moved, 2);
  ASSERT_EQ(w.added.size(), 2u);
  for (const auto& a : w.added) {
    EXPECT_EQ(a.kind, "partition");
    EXPECT_GE((a.b - a.a).norm(), 1.2);
    for (const auto& p : path) EXPECT_GT((p - 0.5 * (a.a + a.b)).norm(), 0.79);
  }
  EXPECT_EQ(w.world.elements.size(), size_t(plan.elements.size() - removed + 2));
}

namespace {

std::vector<V2> corridor_path() {
  SimulatorOptions o;
  o.scenario = "corridor-loop-medium";
  o.clutter = false;
  o.shared_dir = "";
  Simulator sim(FloorPlan{}, o);
  return sim.motion().sample_path(0.1);
}

// How many points of the path within max_range_m see c: a level ray from the sensor's height (1 m) in the world
// reaches it.
int seen_from_path(const World& world, const std::vector<V2>& path, const V2& c, double max_range_m) {
  int seen = 0;
  for (const auto& p : path) {
    const double d = (c - p).norm();
    if (d >= max_range_m) continue;
    const V2 u = (c - p) / d;
    const Hit h = world.cast(Eigen::Vector3d(p.x(), p.y(), 1.0), Eigen::Vector3d(u.x(), u.y(), 0), 30.0);
    if (std::isfinite(h.t) && h.t > d - 0.05) ++seen;
  }
  return seen;
}

}  // namespace

// An added partition is a renovation the robot can find: seen from the path (a ray from the sensor's height at
// 10 or more points of the path within 12 m reaches it). On the corridor loop, partitions used to land in the
// loop's walled-in core (seed 1: both), where nothing could see them.
TEST(Perturb, AddedPartitionsAreSeenFromThePath) {
  const auto path = corridor_path();
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const WorldEdit w = perturb_world(demo_corridor_plan(), path, perturb_family("renovated"), seed);
    const World world(w.world);
    for (const auto& a : w.added) {
      if (a.kind != "partition") continue;
      const V2 c = 0.5 * (a.a + a.b);
      EXPECT_GE(seen_from_path(world, path, c, 12), 10) << "seed " << seed << ": partition at (" << c.x() << ", "
                                                        << c.y() << ")";
    }
  }
}

// A crowd walks where the robot sees it: every person of crowd-15 on the corridor loop (seeds 1-4) has the middle
// of its walking line in sight from 5 or more points of the path within 10 m, and all 15 are placed. They used to
// land in the loop's walled-in core or outside its outer walls.
TEST(Perturb, CrowdWalksWhereTheRobotSeesIt) {
  const auto path = corridor_path();
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const WorldEdit w = perturb_world(demo_corridor_plan(), path, perturb_family("crowd-15"), seed);
    EXPECT_EQ(w.people.size(), 15u) << "seed " << seed;
    const World world(w.world);
    for (const auto& person : w.people) {
      const V2 c = 0.5 * (person.path.front() + person.path.back());
      EXPECT_GE(seen_from_path(world, path, c, 10), 5) << "seed " << seed << ": person walking about (" << c.x()
                                                       << ", " << c.y() << ")";
    }
  }
}

TEST(Perturb, DoorwaysOfTheDemoRoom) {
  const auto d = find_doorways(demo_room_plan());
  ASSERT_EQ(d.size(), 2u);  // the two doors of the room (inner faces; the outer faces are duplicates)
  for (const auto& [a, b] : d) EXPECT_NEAR((b - a).norm(), 1.0, 1e-9);
}

TEST(Perturb, ParseErrors) {
  EXPECT_THROW(parse_perturb("nonsense-family"), std::runtime_error);
  try {
    parse_perturb("asbuilt=0.02,wobble=3");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key 'wobble'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_perturb("glass=2"), std::runtime_error);
  EXPECT_THROW(parse_perturb("remove=1.5"), std::runtime_error);
}

TEST(WorldFile, ReadsEveryKind) {
  const FloorPlan plan = demo_room_plan();
  const std::string f = tmp_file("world_ok.json", R"({"world": {
    "remove": [2], "glass": [7], "move": [{"id": 9, "offset_m": 0.15}],
    "add": [{"a": [5, 6], "b": [7, 6]}],
    "doors": [{"a": [0, 5.75], "b": [0, 6.75], "open": true}],
    "shelves": [{"a": [13, 0], "b": [16, 0]}],
    "people": [{"path": [[8, 8], [9, 9]], "speed": 0.8}]}})");
  const WorldEdit w = load_world_file(f, plan);
  EXPECT_EQ(w.elements[2].change, ElementChange::kRemoved);
  EXPECT_EQ(w.elements[7].change, ElementChange::kGlass);
  EXPECT_EQ(w.elements[9].change, ElementChange::kMoved);
  EXPECT_NEAR(w.elements[9].offset_m, 0.15, 1e-12);
  // 2 and 7 are one face of a two-line wall each: their other faces go with them (WallWithTwoFaces... below).
  EXPECT_EQ(w.world.elements.size(), plan.elements.size() - 4 + 2);
  ASSERT_EQ(w.added.size(), 2u);
  EXPECT_EQ(w.added[1].kind, "door-open");
  EXPECT_EQ(w.furniture.size(), 1u);
  EXPECT_EQ(w.people.size(), 1u);
}

// The error loading a world file of this text gives ("no error" when it loads).
static std::string world_file_error(const FloorPlan& plan, const std::string& name, const std::string& text) {
  try {
    load_world_file(tmp_file(name, text), plan);
  } catch (const std::runtime_error& e) {
    return std::string(e.what());
  }
  return std::string("no error");
}

TEST(WorldFile, BadInputIsOneClearError) {
  const FloorPlan plan = demo_room_plan();
  auto error_of = [&](const std::string& name, const std::string& text) { return world_file_error(plan, name, text); };
  const std::string syntax = error_of("world_syntax.json", "{\"world\": {\"remove\": [2,, 3]}}");
  EXPECT_NE(syntax.find("world_syntax.json: byte 25: JSON syntax error"), std::string::npos) << syntax;
  const std::string field = error_of("world_field.json", R"({"world": {"doors": [{"a": [0, 1], "b": [0, "x"]}]}})");
  EXPECT_NE(field.find("world_field.json: world.doors[0].b: expected [x, y]"), std::string::npos) << field;
  const std::string id = error_of("world_id.json", R"({"world": {"remove": [999]}})");
  EXPECT_NE(id.find("world.remove[0]: expected an element id 0..43"), std::string::npos) << id;
  const std::string key = error_of("world_key.json", R"({"world": {"windows": []}})");
  EXPECT_NE(key.find("world.windows: unknown key"), std::string::npos) << key;
}

// A misspelt key inside an entry was ignored (move's "offset" moved element 12 by 0, "closed" left the door at
// its default), and a move without offset_m moved by 0: each is now one error naming the file, the entry and the
// key, with the keys allowed there.
TEST(WorldFile, UnknownOrMissingKeysInEntriesAreErrors) {
  const FloorPlan plan = demo_room_plan();
  auto error_of = [&](const std::string& name, const std::string& text) { return world_file_error(plan, name, text); };
  const std::string move = error_of("world_mv.json", R"({"world": {"move": [{"id": 12, "offset": 0.2}]}})");
  EXPECT_NE(move.find("world_mv.json: world.move[0].offset: unknown key (allowed: id, offset_m)"), std::string::npos) << move;
  const std::string door = error_of("world_door.json", R"({"world": {"doors": [{"a": [0, 5.75], "b": [0, 6.75], "closed": true}]}})");
  EXPECT_NE(door.find("world_door.json: world.doors[0].closed: unknown key (allowed: a, b, open)"), std::string::npos) << door;
  const std::string shelf = error_of("world_shelf.json", R"({"world": {"shelves": [{"a": [13, 0], "b": [16, 0], "deep": 0.4}]}})");
  EXPECT_NE(shelf.find("world.shelves[0].deep: unknown key (allowed: a, b, depth, height)"), std::string::npos) << shelf;
  const std::string add = error_of("world_add.json", R"({"world": {"add": [{"a": [5, 6], "b": [7, 6], "c": [1, 1]}]}})");
  EXPECT_NE(add.find("world.add[0].c: unknown key (allowed: a, b)"), std::string::npos) << add;
  const std::string person = error_of("world_person.json", R"({"world": {"people": [{"path": [[8, 8], [9, 9]], "sped": 3}]}})");
  EXPECT_NE(person.find("world.people[0].sped: unknown key (allowed: path, speed)"), std::string::npos) << person;
  const std::string missing = error_of("world_nooff.json", R"({"world": {"move": [{"id": 12}]}})");
  EXPECT_NE(missing.find("world_nooff.json: world.move[0].offset_m: missing"), std::string::npos) << missing;
  const std::string twice = error_of("world_twice.json", R"({"world": {"move": [{"id": 12, "offset_m": 0.1}, {"id": 12, "offset_m": 0.2}]}})");
  EXPECT_NE(twice.find("world.move[1].id: element 12 is moved twice"), std::string::npos) << twice;
  const std::string top = error_of("world_top.json", R"({"world": {"windows": []}})");
  EXPECT_NE(top.find("world.windows: unknown key (allowed: plan, remove, glass, move, add, doors, shelves, people)"),
            std::string::npos) << top;
}

// A wall drawn with two faces (the demo room's outer walls: 0.25 m apart) is one wall in a world file as with
// --perturb: remove / glass / move of one face take the other face too (the same change, the same displacement)
// unless it is named itself, and the truth lists both. It used to act on the named line alone, so the diff saw
// the other face "moved" by the wall's thickness.
TEST(WorldFile, WallWithTwoFacesChangesAsAWhole) {
  const FloorPlan plan = demo_room_plan();
  // 2: south wall x 6..10 (inner face, y 0), 16 its outer face (y -0.25); 7 / 21 the north wall's; 9 / 23 the
  // north wall x 13..16; 12 / 26 the east wall's lower part. Pillar faces (28..35) have no other face.
  ASSERT_EQ(other_face(plan, 2), 16);
  ASSERT_EQ(other_face(plan, 16), 2);
  ASSERT_EQ(other_face(plan, 7), 21);
  ASSERT_EQ(other_face(plan, 9), 23);
  ASSERT_EQ(other_face(plan, 12), 26);
  const WorldEdit w = load_world_file(tmp_file("world_faces.json", R"({"world": {
    "remove": [2], "glass": [7], "move": [{"id": 9, "offset_m": 0.15}, {"id": 12, "offset_m": -0.1},
                                          {"id": 26, "offset_m": 0.05}]}})"), plan);
  EXPECT_EQ(w.elements[16].change, ElementChange::kRemoved);
  EXPECT_EQ(w.elements[21].change, ElementChange::kGlass);
  EXPECT_EQ(w.elements[23].change, ElementChange::kMoved);
  EXPECT_NEAR(w.elements[23].offset_m, 0.15, 1e-12);  // same direction a->b on both faces: the same offset
  // Both faces named: each its own offset (no double move).
  EXPECT_NEAR(w.elements[12].offset_m, -0.1, 1e-12);
  EXPECT_NEAR(w.elements[26].offset_m, 0.05, 1e-12);
  // The world: 2 + 16 and 7 + 21 gone, nothing else.
  EXPECT_EQ(w.world.elements.size(), plan.elements.size() - 4);
  // The truth lists both faces.
  const auto t = nlohmann::json::parse(w.truth_json(plan));
  EXPECT_EQ(t["elements"][16]["change"], "removed");
  EXPECT_EQ(t["elements"][21]["change"], "glass");
  EXPECT_EQ(t["elements"][23]["change"], "moved");
  int changed = 0;
  for (const auto& e : t["elements"]) changed += e["change"] != "unchanged";
  EXPECT_EQ(changed, 8);
  // --perturb's renovation uses the same notion of a wall's other face: every removed / moved wall has its other
  // face changed the same way.
  PerturbOptions p;
  p.remove = 2;
  p.move = 2;
  const WorldEdit r = perturb_world(plan, room_path(), p, 5);
  for (size_t i = 0; i < plan.elements.size(); ++i) {
    const int f = other_face(plan, int(i));
    if (f >= 0 && r.elements[i].change != ElementChange::kUnchanged) EXPECT_EQ(r.elements[size_t(f)].change, r.elements[i].change) << i;
  }
}

// "doors moved": a doorway shifted along its wall. Deterministic per seed; the truth says what closed and
// what opened, and the world's wall ends (both faces, the jambs) are where the truth puts the new opening.
TEST(Perturb, DoorsMovedDeterministicAndTruthMatchesTheWorld) {
  const FloorPlan plan = demo_room_plan();
  const auto path = room_path();
  const PerturbOptions o = perturb_family("doors-moved");
  EXPECT_EQ(o.doors_moved, 2);
  const WorldEdit a = perturb_world(plan, path, o, 1), b = perturb_world(plan, path, o, 1);
  EXPECT_EQ(a.truth_json(plan), b.truth_json(plan));
  ASSERT_EQ(a.world.elements.size(), plan.elements.size());  // nothing removed or added: ends moved
  for (size_t i = 0; i < a.world.elements.size(); ++i) {
    EXPECT_EQ(a.world.elements[i].a, b.world.elements[i].a);
    EXPECT_EQ(a.world.elements[i].b, b.world.elements[i].b);
  }
  ASSERT_EQ(a.doors_moved.size(), 2u) << a.truth_json(plan);  // the room's two doorways
  bool differs = false;
  for (uint64_t seed : {2u, 3u}) {
    const WorldEdit c = perturb_world(plan, path, o, seed);
    differs = differs || c.truth_json(plan) != a.truth_json(plan);
  }
  EXPECT_TRUE(differs);
  for (const auto& d : a.doors_moved) {
    EXPECT_GE(std::abs(d.shift_m), o.door_shift_min_m - 1e-9);
    EXPECT_LE(std::abs(d.shift_m), o.door_shift_max_m + 1e-9);
    EXPECT_NEAR((d.to_a - d.from_a).norm(), std::abs(d.shift_m), 1e-9);
    EXPECT_NEAR((d.to_b - d.to_a).norm(), (d.from_b - d.from_a).norm(), 1e-9);
    // Closed + opened pieces: each as long as the shift (shift < width here).
    EXPECT_NEAR((d.closed_b - d.closed_a).norm(), std::abs(d.shift_m), 1e-9);
    EXPECT_NEAR((d.opened_b - d.opened_a).norm(), std::abs(d.shift_m), 1e-9);
    // Both faces and both jambs: at least 6 elements (4 faces, 2 jambs in room.json).
    EXPECT_GE(d.elements.size(), 6u);
    for (int id : d.elements) {
      EXPECT_EQ(a.elements[size_t(id)].change, ElementChange::kDoorMoved);
      EXPECT_EQ(change_name(a.elements[size_t(id)].change), std::string("door-moved"));
    }
    // The world has wall ends at the new opening's ends (inner face) and none at the old ones.
    auto has_end = [&](const V2& x) {
      for (const auto& e : a.world.elements)
        if ((e.a - x).norm() < 1e-9 || (e.b - x).norm() < 1e-9) return true;
      return false;
    };
    EXPECT_TRUE(has_end(d.to_a));
    EXPECT_TRUE(has_end(d.to_b));
    EXPECT_FALSE(has_end(d.from_a));
    EXPECT_FALSE(has_end(d.from_b));
    // The closed piece is wall now: a world segment covers its midpoint.
    const V2 mid = 0.5 * (d.closed_a + d.closed_b);
    double dmin = 1e9;
    nearest_element_brute_force(a.world, mid, &dmin);
    EXPECT_LT(dmin, 1e-6);
  }
  // The truth JSON lists them.
  EXPECT_NE(a.truth_json(plan).find("\"doors_moved\""), std::string::npos);
  EXPECT_NE(a.truth_json(plan).find("\"door-moved\""), std::string::npos);
  // Bad values name the key.
  EXPECT_THROW(parse_perturb("doors_moved=1.5"), std::runtime_error);
  EXPECT_THROW(parse_perturb("door_shift_min=0.8,door_shift_max=0.5"), std::runtime_error);
}
