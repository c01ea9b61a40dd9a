// The ceilings of one building floor as the height estimator sees them: areas (plan-frame polygons) with
// their floor-to-ceiling height (flat or sloped) from the building, or learned online per area where the
// building gives none, and the floor's default elsewhere. Plain data (the segmenter node fills it from a
// building file, modules/floorplan); no LCM, no plan types here.
//
// With the sensor's plan pose (the localizer's feedback) every ceiling inlier is looked up in the area
// under it, so a ceiling seen across an area boundary gives each point its own area's height: z never
// jumps when the robot crosses from a low corridor into a high hall.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace fploc::seg {

struct AreaCeiling {
  std::string name;
  std::vector<Eigen::Vector2d> polygon;           // plan frame [m], >= 3 vertices
  double height_m = 0;                            // floor-to-ceiling at `origin`; 0 = unknown (learned)
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  Eigen::Vector2d slope = Eigen::Vector2d::Zero();  // dz/dx, dz/dy (a sloped ceiling)
  bool contains(const Eigen::Vector2d& p) const;
};

struct AreaCeilingMap {
  std::string floor;                  // the building floor's name (diagnostics)
  double default_height_m = 0;        // outside every area; 0 = unknown (learned)
  std::vector<AreaCeiling> areas;     // the first area containing a point wins
  // Index of the area containing p, -1 = the floor's default region. Bounding boxes first.
  int area_at(const Eigen::Vector2d& p) const;
  const std::string& name(int area) const;
  void finish();                      // computes the bounding boxes (call after filling `areas`)
  std::vector<Eigen::Vector4d> bbox;  // per area: min x, min y, max x, max y
};

// The sensor's pose in the plan frame (x, y, yaw) from the localizer, at utime.
struct PlanPose {
  int64_t utime = 0;
  double x = 0, y = 0, yaw = 0;
  bool valid = false;
};

// Heights per area: the building's where it gives one, else learned online (a running median of
// ceiling + ground distance, fed only from scans whose ceiling lies in one area).
class AreaHeights {
 public:
  void reset(const AreaCeilingMap& map, int window);
  // Floor-to-ceiling height at p in `area` (-1 = default region); 0 = not known yet.
  double height_at(int area, const Eigen::Vector2d& p) const;
  bool known(int area) const;     // from the building
  bool learned(int area) const;   // learned online (not from the building)
  void learn(int area, double h);
  int samples(int area) const;

 private:
  struct Slot {
    double given = 0;   // from the building (0 = none)
    Eigen::Vector2d origin = Eigen::Vector2d::Zero(), slope = Eigen::Vector2d::Zero();
    std::deque<double> seen;
    double median = 0;
  };
  const Slot& slot(int area) const { return slots_[size_t(area + 1)]; }
  std::vector<Slot> slots_;  // [0] = default region, [i + 1] = area i
  int window_ = 51;
};

}  // namespace fploc::seg
