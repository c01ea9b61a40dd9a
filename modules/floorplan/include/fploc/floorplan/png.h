// Writing pictures of plans: an RGB image (row-major, 3 bytes per pixel) as a PNG file (libpng, which
// the floor-plan library already links to read occupancy maps), and text on such an image (FreeType with
// Debian's DejaVu Sans, fonts-dejavu-core) for legends and scale bars.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fploc {

// Throws std::runtime_error naming `path` when it cannot be written or img.size() != w * h * 3.
void write_rgb_png(const std::string& path, int w, int h, const std::vector<uint8_t>& img);

// An RGB picture being drawn: w x h pixels, row-major, 3 bytes each (what write_rgb_png writes).
struct RgbImage {
  int w = 0, h = 0;
  std::vector<uint8_t> px;
  RgbImage(int width, int height, uint8_t grey = 255) : w(width), h(height), px(size_t(width) * height * 3, grey) {}
  // Pixels outside the image are ignored.
  void set(int x, int y, const uint8_t rgb[3]);
  // The rectangle [x0, x1) x [y0, y1), clipped to the image; alpha < 1 blends it over what is there.
  void fill_rect(int x0, int y0, int x1, int y1, const uint8_t rgb[3], double alpha = 1);
  void write_png(const std::string& path) const { write_rgb_png(path, w, h, px); }
};

// Draws `text` (UTF-8; one line) with the left end of its baseline at (x, y) px, `size_px` high (the em), in
// `rgb`, anti-aliased over what is there. Returns its advance width in px. The font is the file
// $FPLOC_FONT, else DejaVu Sans (/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf); when it cannot be loaded the
// text is not drawn, the width is an estimate and the first call says why on stderr.
int draw_text(RgbImage& img, int x, int y, const std::string& text, int size_px, const uint8_t rgb[3]);
// The advance width draw_text would give, without drawing.
int text_width(const std::string& text, int size_px);

// Plan coordinates on a picture (fploc map render, fploc occupancy --png), so that a start pose can be read off it:
// a light grid every `step_m` metres over the plan area, the axes x = 0 and y = 0 darker and the origin ringed
// when in view, and tick labels in metres in margins left of the area (y) and below it (x).
struct PlanGrid {
  double step_m = 1;       // 1, 2 or 5 x 10^k m
  int font_px = 12;
  int left_px = 0;         // the margin the y labels need, left of the area
  int bottom_px = 0;       // the margin the x labels need, below the area
  std::string label(double v) const;  // "12", "-2.5", "0" (never "-0")
};
// The grid for a plan area showing the box (plan metres) at `px_per_m`: the smallest step whose lines are at least
// five font sizes and two more than their widest label apart, and the margins its labels need.
PlanGrid plan_grid(double box_min_x, double box_min_y, double box_max_x, double box_max_y, double px_per_m, int font_px);
// A plan area of a picture: the pixel rectangle [x0, x1) x [y0, y1) and its mapping, plan metres <-> pixels (column,
// row; any rotation, e.g. an occupancy map's origin yaw).
struct PlanArea {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double ox = 0, oy = 0;   // the pixel position of plan (0, 0)
  double ux = 1, uy = 0;   // pixels per metre along plan x: (column, row) step
  double vx = 0, vy = -1;  // pixels per metre along plan y
  void to_px(double x, double y, double* c, double* r) const { *c = ox + ux * x + vx * y, *r = oy + uy * x + vy * y; }
  void to_m(double c, double r, double* x, double* y) const;
};
// The grid lines and the origin, blended over what the area holds (draw the plan over them).
void draw_plan_grid_lines(RgbImage& img, const PlanArea& area, const PlanGrid& grid);
// Ticks and labels in the margins: x where each line x = k step leaves the area's bottom edge, y where each line
// y = k step leaves its left edge; "m" in the corner between the margins. Labels that would overlap are left out.
void draw_plan_grid_labels(RgbImage& img, const PlanArea& area, const PlanGrid& grid);

}  // namespace fploc
