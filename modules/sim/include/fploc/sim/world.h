// The simulated 3D world: a floor plan extruded into vertical walls and pillars between a floor (z = 0)
// and a ceiling (optional sloped or missing patches), plus clutter that is NOT in the plan (furniture
// boxes, moving people). One ray query returns the distance, what was hit (a Label) and the plan element.
//
// Ray casting: plan walls go into a uniform 2D grid (cells of `grid_cell_m`) walked with a DDA; floor,
// ceiling, boxes and cylinders are intersected analytically. The floor/ceiling distance is computed first
// and bounds the grid walk, so near-horizontal beams visit only a few cells.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc::sim {

// What a return hit. kWall = a plan segment or arc, kPillar = a plan circle.
enum class Label : uint8_t { kNone = 0, kFloor = 1, kCeiling = 2, kWall = 3, kPillar = 4, kClutter = 5 };
const char* label_name(Label l);
constexpr int kNumLabels = 6;

struct WorldConfig {
  double ceiling_height_m = 3.0;
  // Elements whose layer name contains one of these (case-insensitive) are windows: wall below the sill
  // and above the head, open (glass, no return) between.
  std::vector<std::string> window_layers{"window", "glass", "crystal"};
  double window_sill_m = 0.9;
  double window_head_m = 2.2;
  double grid_cell_m = 0.5;
};

// Point in a simple polygon (even-odd rule; points on an edge may go either way).
bool polygon_contains(const std::vector<Eigen::Vector2d>& poly, double x, double y);
Box2 polygon_bounds(const std::vector<Eigen::Vector2d>& poly);

// A ceiling region (axis-aligned box in the plan frame, or a polygon when `polygon` is set: then `box`
// is its bounding box) that is either missing (rays pass) or a plane z = h0 + slope.dot(xy - box.min).
// Where patches overlap, the first one added that contains a point owns it (ceiling_at and the rays alike).
struct CeilingPatch {
  Box2 box;
  bool open = false;
  double h0 = 3.0;
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> polygon;  // empty = the box itself
  double height(double x, double y) const { return h0 + slope.x() * (x - box.min.x()) + slope.y() * (y - box.min.y()); }
  bool contains(double x, double y) const;
};

// A region of the floor that is not at z = 0 (a ramp, the flight of a stairs, the floor of the storey
// below seen from above): a polygon with the plane z = h0 + slope.dot(xy - origin). The first patch
// containing a point wins; elsewhere the floor is at z = 0.
struct GroundPatch {
  std::string name;
  std::vector<Eigen::Vector2d> polygon;
  double h0 = 0;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();
  Box2 box;  // bounding box (set by World::add_ground_patch)
  double height(double x, double y) const { return h0 + slope.x() * (x - origin.x()) + slope.y() * (y - origin.y()); }
};

// Furniture: an oriented box standing on z0.
struct Furniture {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double yaw = 0;
  Eigen::Vector2d half = Eigen::Vector2d(0.5, 0.5);  // half extents in its own frame
  double z0 = 0, z1 = 0.75;
  uint8_t reflectivity = 30;
  bool ground = false;  // part of the floor (a door threshold): labelled kFloor, not clutter
};

// A walking person: a vertical cylinder moving back and forth along a polyline at constant speed.
struct Person {
  std::vector<Eigen::Vector2d> path;  // at least one point
  double speed = 1.0;                 // m/s
  double phase_s = 0;                 // time offset
  double radius = 0.22;
  double height = 1.75;
  Eigen::Vector2d position(double t) const;
};

struct Hit {
  double t = 0;                      // distance along the (unit) ray [m]; infinity when nothing was hit
  Label label = Label::kNone;
  int32_t element = -1;              // plan element id for kWall/kPillar, clutter index for kClutter, else -1
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  uint8_t reflectivity = 0;
};

class World {
 public:
  explicit World(const FloorPlan& plan, WorldConfig cfg = {});

  void add_furniture(const Furniture& f);
  void add_person(const Person& p) { people_.push_back(p); }
  void add_ceiling_patch(const CeilingPatch& p);
  void add_ground_patch(GroundPatch p);
  const std::vector<GroundPatch>& ground_patches() const { return ground_; }
  // Floor height at (x, y): the ground patch there, else 0 (thresholds not included).
  double ground_at(double x, double y) const;
  void clear_clutter() {
    furniture_.clear();
    furn_cs_.clear();
    people_.clear();
  }

  // Moves the people to time t (call before casting rays for that time).
  void set_time(double t);
  // First hit of the ray o + t d (d unit length) with t in (0, t_max].
  Hit cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max) const;

  const FloorPlan& plan() const { return plan_; }
  const WorldConfig& config() const { return cfg_; }
  const std::vector<Furniture>& furniture() const { return furniture_; }
  const std::vector<Person>& people() const { return people_; }
  const std::vector<CeilingPatch>& ceiling_patches() const { return patches_; }
  // Ceiling height at (x, y) (NaN where the ceiling is missing or outside the building).
  double ceiling_at(double x, double y) const;
  // Plan bounds (the building: the ceiling exists only inside).
  const Box2& bounds() const { return bounds_; }
  // Clearance of a plan point from walls, pillars and furniture (people excluded).
  double static_clearance(const Eigen::Vector2d& p) const;

 private:
  struct Wall {
    ElementKind kind;
    Eigen::Vector2d a, b, c;
    double r = 0, a0 = 0, a1 = 0;
    float z[4];      // up to two solid z intervals [z0,z1] and [z2,z3]
    int nz = 1;
    Label label;
    int32_t element;
    uint8_t reflectivity;
  };
  bool hit_wall(const Wall& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax, Hit& h) const;
  double ceiling_t(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tmax) const;
  bool in_ground_patch(double x, double y) const;

  FloorPlan plan_;
  WorldConfig cfg_;
  std::vector<Wall> walls_;
  Box2 bounds_;
  double wall_top_ = 3.0;
  // Grid (CSR).
  Eigen::Vector2d grid_min_;
  int nx_ = 0, ny_ = 0;
  double cell_ = 0.5;
  std::vector<uint32_t> cell_start_;
  std::vector<uint32_t> cell_walls_;

  std::vector<CeilingPatch> patches_;
  std::vector<GroundPatch> ground_;
  double wall_bottom_ = 0;  // walls reach down to the lowest ground patch
  std::vector<Furniture> furniture_;
  std::vector<Eigen::Vector3d> furn_cs_;  // cos(yaw), sin(yaw), bounding radius
  std::vector<Person> people_;
  std::vector<Eigen::Vector2d> people_pos_;
};

}  // namespace fploc::sim
