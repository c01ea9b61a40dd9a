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

}  // namespace fploc
