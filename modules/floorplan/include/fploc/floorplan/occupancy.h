// Occupancy maps as floor plans: the ROS map_server format (YAML + PGM/PNG) read into an occupancy grid
// and its occupied boundaries vectorised into line segments, so a map that an AMCL setup already uses is a
// plan everywhere a plan is (load_floor_plan dispatches .yaml / .yml here).
//
//   OccupancyGrid g = fploc::read_occupancy_map("map.yaml");
//   VectoriseStats st;
//   FloorPlan plan = fploc::vectorise_occupancy(g, {}, &st);   // st.max_error_m <= tolerance
//
// map_server semantics (ROS 1 map_server / nav2 map_io): YAML keys image (relative to the YAML's folder),
// resolution [m/cell], origin [x, y, yaw] (pose of the lower-left cell's corner; yaw counter-clockwise),
// negate, occupied_thresh, free_thresh, mode (trinary | scale | raw; default trinary). A pixel's colour is
// the mean of its colour channels; p = (255 - mean) / 255 (negate: mean / 255). trinary: p > occupied_thresh
// occupied (100), p < free_thresh free (0), else unknown (-1). scale: as trinary but values between the
// thresholds map linearly to 1..99 and a pixel with alpha < 255 is unknown. raw: the value is the mean itself
// (0..100 an occupancy percentage, anything else unknown).
//
// Vectorisation (the method, its error in docs/notes/real2d.md):
//  1. occupied cells: value > 100 * occupied_thresh (trinary: the 100s);
//  2. boundary cells: occupied cells with a 4-neighbour that is not occupied (free or unknown) or off the map;
//  3. boundary cells are chained into polylines along 8-neighbours (a walk that starts at chain ends, prefers
//     4-neighbours and never revisits a cell), so every boundary cell is on exactly one chain;
//  4. each chain (cell centres) is simplified by Douglas-Peucker with `tolerance_cells`; a chain of one cell
//     becomes a segment a tenth of a cell long through its centre.
// Every boundary cell centre is then within tolerance of its chain's segments (the stats measure it).
//
// Errors: std::runtime_error "FILE: FIELD: what", e.g. "map.yaml: resolution: must be > 0, got -1",
// "map.pgm: byte 15: truncated pixel data (expected 92700 bytes, got 120)", "map.pgm: byte 9233: the pixel data is
// longer than the header's 180x51 says: 83520 bytes after the image (464 more rows of 180)" (trailing whitespace
// is fine), "map.pgm: byte 184587: pixel data truncated: got 46396 of 180x515 = 92700 values" (ASCII P2).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/floorplan/plan.h"

namespace fploc {

enum class OccupancyMode { kTrinary, kScale, kRaw };

struct MapYaml {
  std::string image;          // as written in the YAML
  std::string image_path;     // resolved against the YAML's folder
  double resolution = 0;
  double origin_x = 0, origin_y = 0, origin_yaw = 0;
  bool negate = false;
  double occupied_thresh = 0.65, free_thresh = 0.196;
  OccupancyMode mode = OccupancyMode::kTrinary;
  // Keys map_server does not know (ROS ignores them, so do we): "SOURCE: line N: unknown key 'K' (ignored; ...)".
  // read_map_yaml prints them to stderr as warnings.
  std::vector<std::string> warnings;
};

// A grayscale (or colour-averaged) image with optional alpha, row 0 at the top (as stored).
struct GrayImage {
  int width = 0, height = 0;
  std::vector<uint8_t> value;  // mean of the colour channels, 0..255 (16-bit PGMs scaled to 8 bit)
  std::vector<uint8_t> alpha;  // empty = opaque
};

struct OccupancyGrid {
  int width = 0, height = 0;
  double resolution = 0;
  double origin_x = 0, origin_y = 0, origin_yaw = 0;
  double occupied_thresh = 0.65;
  double yaml_occupied_thresh = 0.65;  // the YAML's occupied_thresh (occupied_thresh is 0.995 for trinary / scale)
  // ROS nav_msgs/OccupancyGrid layout: row 0 is the BOTTOM row (y = origin); -1 unknown, 0..100 occupancy.
  std::vector<int8_t> data;
  std::string source;
  int8_t at(int i, int j) const { return data[size_t(j) * width + i]; }
  bool occupied(int i, int j) const { return at(i, j) > 100.0 * occupied_thresh; }
  // World position of cell (i, j)'s centre.
  Eigen::Vector2d cell_centre(int i, int j) const;
};

MapYaml parse_map_yaml(const std::string& text, const std::string& source);  // throws "SOURCE: FIELD: ..."
MapYaml read_map_yaml(const std::string& path);
GrayImage read_pgm(const std::string& bytes, const std::string& source);      // P2 / P5, 8 or 16 bit
GrayImage read_image(const std::string& path);                                // .pgm or .png (libpng)
OccupancyGrid occupancy_from_image(const GrayImage& img, const MapYaml& y, const std::string& source);
OccupancyGrid read_occupancy_map(const std::string& yaml_path);

struct VectoriseOptions {
  double tolerance_cells = 0.5;  // Douglas-Peucker tolerance (cells)
};

struct VectoriseStats {
  size_t occupied_cells = 0, boundary_cells = 0, chains = 0, segments = 0;
  // Distance of each boundary cell centre to its chain's simplified polyline [m].
  double max_error_m = 0, mean_error_m = 0;
};

FloorPlan vectorise_occupancy(const OccupancyGrid& g, const VectoriseOptions& o = {}, VectoriseStats* stats = nullptr);

// YAML path -> plan (what load_floor_plan does for .yaml / .yml); elements on layer "occupied".
// An occupancy map with no occupied cell (nothing to localize against): throws "YAML: image 'IMG': no occupied cells
// (...occupied_thresh T of the YAML...)", the same words from `fploc occupancy`, replay and `fploc launch --check`.
void require_occupied_cells(const OccupancyGrid& g, const FloorPlan& vectorised, const std::string& yaml_path);
FloorPlan load_occupancy_plan(const std::string& yaml_path, VectoriseStats* stats = nullptr);

}  // namespace fploc
