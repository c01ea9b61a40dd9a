// World != plan: the building the simulator scans, built from the plan the localizer gets, either by
// named, seeded perturbations (as-built wall offsets, a global scale error, renovations (walls removed,
// moved, partitions added, doorways moved along their wall), glass, doors,
// crowds, shelving) or from a world file. The ground truth of the difference (which plan elements were
// moved / removed / turned to glass, which structure was added, by how much) is kept as JSON.
//
//   PerturbOptions p = perturb_family("renovated");       // or parse_perturb("asbuilt=0.02,remove=1,add=2")
//   WorldEdit w = perturb_world(plan, path, p, seed);      // path: the sensor's path (kept clear)
//   World world(w.world); for (auto& f : w.furniture) world.add_furniture(f); ...
//
// World file (`fploc sim --world FILE`): either any plan file (.dxf/.csv/.json: the world's walls), or a
// JSON object with a "world" key:
//   {"world": {"plan": "room.json",                 // path relative to this file (any plan format)
//              "remove": [2, 7], "glass": [5],       // plan element ids (a wall with its other face, see below)
//              "move": [{"id": 9, "offset_m": 0.15}],// along the segment's left normal (a->b turned +90 deg); required
//              "add": [{"a": [x, y], "b": [x, y]}],  // partitions not in the plan
//              "doors": [{"a": [x, y], "b": [x, y], "open": false}],   // a doorway a-b: closed leaf or open (hinged at a)
//              "shelves": [{"a": [x, y], "b": [x, y], "depth": 0.4, "height": 2.0}],  // box along a-b, on its left
//              "people": [{"path": [[x, y], ...], "speed": 1.0}]}}
// A wall drawn with two lines is one wall, as with --perturb: an id in remove / glass / move takes its other face
// (other_face()) with it (the same change, the same displacement), unless that face is named itself; the truth
// lists both faces. Every key is checked: an unknown one (at the top or inside an entry) or a missing required one
// (a, b; move's id and offset_m; people's path) is an error.
// Errors: std::runtime_error "FILE: byte N: ..." (syntax) or "FILE: world.doors[1].a: expected [x, y]" or
// "FILE: world.move[0].offset: unknown key (allowed: id, offset_m)".
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"
#include "fploc/sim/world.h"

namespace fploc::sim {

struct PerturbOptions {
  std::string name;               // family name or the spec string (recorded in the truth)
  double asbuilt_sigma_m = 0;     // every wall endpoint / pillar centre displaced by N(0, sigma) per axis
  double scale = 0;               // world = plan * (1 + scale) about the plan's centre (0.005: drawing 0.5 % too small)
  int remove = 0;                 // walls (with their other face) and pillars taken out
  int add = 0;                    // partitions 1.2-3 m added in free space
  int move = 0;                   // walls moved along their normal by move_min..move_max (either side)
  double move_min_m = 0.10, move_max_m = 0.25;
  double glass = 0;               // fraction of the visible wall length turned to full-height glass (no return)
  bool doors = false;             // doorways of the plan get a door leaf, open or closed at random
  double shelves = 0;             // fraction of the wall length behind 2 m shelving (SimulatorOptions::wall_clutter)
  int crowd = 0;                  // people walking near the path
  int doors_moved = 0;            // doorways shifted along their wall by door_shift_min..max (either way)
  double door_shift_min_m = 0.4, door_shift_max_m = 0.9;
  bool any() const {
    return asbuilt_sigma_m > 0 || scale != 0 || remove || add || move || glass > 0 || doors || shelves > 0 || crowd ||
           doors_moved;
  }
};

// "key=value,..." with the keys of perturb_keys() (asbuilt, scale, remove, add, move, move_min, move_max, glass,
// doors, shelves, crowd, doors_moved, door_shift_min, door_shift_max); or a family name.
// Throws on an unknown key/family or a bad value.
PerturbOptions parse_perturb(const std::string& spec);
// The --perturb keys: the one list parse_perturb reads them by, and help texts are made from.
struct PerturbKey {
  const char* name;
  const char* doc;       // what it does, for help texts
  const char* expected;  // the values it takes, for errors
  bool (*ok)(double);
  void (*set)(PerturbOptions&, double);
};
const std::vector<PerturbKey>& perturb_keys();
// "asbuilt: every wall end ...; scale: ...; ..." (every key of perturb_keys() with its doc).
std::string perturb_keys_help();
// The bench families: clean, asbuilt-2cm, asbuilt-5cm, scale-0.5pct, renovated, glass, shelves, doors,
// crowd-15, mixed, doors-moved. Throws on an unknown name (listing the names).
PerturbOptions perturb_family(const std::string& name);
std::vector<std::string> perturb_family_names();

// Status of one plan element in the world.
// kDoorMoved: a wall face or jamb of a doorway that was shifted along its wall (the face grew or lost a
// piece at that end, the jamb moved with the opening; see DoorMovedTruth).
enum class ElementChange : uint8_t { kUnchanged = 0, kMoved = 1, kRemoved = 2, kGlass = 3, kDoorMoved = 4 };
const char* change_name(ElementChange c);

struct ElementTruth {
  ElementChange change = ElementChange::kUnchanged;
  double offset_m = 0;       // signed displacement along the segment's left normal (mean of both ends; circles: |dc|)
  double max_shift_m = 0;    // largest displacement of any point of the element (as-built + moves)
  double rotation_rad = 0;   // direction change (segments)
};

struct AddedTruth {
  std::string kind;          // "partition", "door-closed", "door-open"
  Eigen::Vector2d a, b;
};

// A doorway moved along its wall by shift_m (along from_a -> from_b): the old opening from_a-from_b is now
// to_a-to_b; closed_a-closed_b (part of the old opening) is wall now, opened_a-opened_b (part of a drawn
// wall) is open now, both along the face from_a-from_b lies on.
struct DoorMovedTruth {
  Eigen::Vector2d from_a, from_b, to_a, to_b, closed_a, closed_b, opened_a, opened_b;
  double shift_m = 0;
  std::vector<int> elements;  // plan elements that changed (faces, jambs)
};

struct WorldEdit {
  FloorPlan world;                       // the walls the sensor sees (world-only structure included)
  std::vector<Furniture> furniture;      // shelves of a world file
  std::vector<Person> people;
  double wall_clutter = 0;               // shelving fraction for the simulator's wall clutter
  std::vector<ElementTruth> elements;    // one per plan element
  std::vector<AddedTruth> added;
  std::vector<DoorMovedTruth> doors_moved;
  double scale = 0;
  double asbuilt_sigma_m = 0;            // the as-built displacement's sigma (0: none, or a world file)
  std::string source;                    // family / spec / world file
  uint64_t seed = 0;
  // The truth as JSON text: {"source", "seed", "scale", "asbuilt_sigma_m", "plan_elements", "elements": [{"id", "change",
  // "offset_m", "max_shift_m", "rotation_deg", "length_m"}], "added": [{"kind", "a", "b", "length_m"}],
  // "shelves_fraction", "people", "doors_moved": [{"from", "to", "closed", "opened" (each [[x, y], [x, y]]),
  // "shift_m", "elements"}]}.
  std::string truth_json(const FloorPlan& plan) const;
};

// Deterministic for (plan, path, options, seed). `path` are points of the sensor's path: added
// structure, doors and people keep clear of it.
WorldEdit perturb_world(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& path, const PerturbOptions& o,
                        uint64_t seed);

// Reads a world file (see above) against `plan` (ids refer to it).
WorldEdit load_world_file(const std::string& path, const FloorPlan& plan, const std::vector<std::string>& layers = {},
                          const std::string& units = "");

// The other face of a wall drawn with two lines: the nearest parallel segment 2-40 cm away overlapping at least
// half of the shorter of the two; -1 when there is none (or the element is not a segment). Used by --perturb
// (remove, move, glass) and by world files alike.
int other_face(const FloorPlan& plan, int id);

// Doorways of a plan: gaps of 0.7-1.3 m between collinear segment ends (one per wall: the inner face).
std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> find_doorways(const FloorPlan& plan);

}  // namespace fploc::sim
