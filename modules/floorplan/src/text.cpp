// Text on RgbImage with FreeType (fploc/floorplan/png.h).
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <mutex>

#include "fploc/floorplan/png.h"

namespace fploc {

void RgbImage::set(int x, int y, const uint8_t rgb[3]) {
  if (x < 0 || y < 0 || x >= w || y >= h) return;
  uint8_t* p = &px[(size_t(y) * w + x) * 3];
  p[0] = rgb[0], p[1] = rgb[1], p[2] = rgb[2];
}

void RgbImage::fill_rect(int x0, int y0, int x1, int y1, const uint8_t rgb[3], double alpha) {
  x0 = std::max(0, x0), y0 = std::max(0, y0), x1 = std::min(w, x1), y1 = std::min(h, y1);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      uint8_t* p = &px[(size_t(y) * w + x) * 3];
      for (int k = 0; k < 3; ++k) p[k] = uint8_t(std::lround(alpha * rgb[k] + (1 - alpha) * p[k]));
    }
}

namespace {

// One face for the process (FreeType handles are not thread-safe: the mutex guards every use).
struct Font {
  std::mutex mu;
  FT_Library lib = nullptr;
  FT_Face face = nullptr;
  Font() {
    const char* env = std::getenv("FPLOC_FONT");
    const std::string path = env && *env ? env : "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
    if (FT_Init_FreeType(&lib) != 0) {
      std::cerr << "fploc: FreeType does not start: pictures without text\n";
      lib = nullptr;
      return;
    }
    if (FT_New_Face(lib, path.c_str(), 0, &face) != 0) {
      std::cerr << "fploc: font " << path << " cannot be loaded (Debian: fonts-dejavu-core; or set FPLOC_FONT): pictures "
                << "without text\n";
      face = nullptr;
    }
  }
  ~Font() {
    if (face) FT_Done_Face(face);
    if (lib) FT_Done_FreeType(lib);
  }
};
Font& font() {
  static Font f;
  return f;
}

// UTF-8 -> code points (malformed bytes as themselves).
std::vector<uint32_t> code_points(const std::string& s) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < s.size();) {
    const unsigned char c = (unsigned char)s[i];
    int n = c >= 0xf0 ? 3 : c >= 0xe0 ? 2 : c >= 0xc0 ? 1 : 0;
    if (n && i + size_t(n) >= s.size()) n = 0;
    uint32_t cp = n == 0 ? c : c & (0x3f >> n);
    for (int k = 1; k <= n; ++k) cp = (cp << 6) | ((unsigned char)s[i + k] & 0x3f);
    out.push_back(cp);
    i += size_t(n) + 1;
  }
  return out;
}

int layout(RgbImage* img, int x, int y, const std::string& text, int size_px, const uint8_t rgb[3]) {
  Font& f = font();
  std::lock_guard<std::mutex> lock(f.mu);
  if (!f.face) return int(0.6 * size_px * double(code_points(text).size()));
  FT_Set_Pixel_Sizes(f.face, 0, FT_UInt(std::max(1, size_px)));
  int pen = 0;
  for (uint32_t cp : code_points(text)) {
    if (FT_Load_Char(f.face, cp, img ? FT_LOAD_RENDER : FT_LOAD_DEFAULT) != 0) continue;
    const FT_GlyphSlot g = f.face->glyph;
    if (img) {
      const FT_Bitmap& b = g->bitmap;
      for (unsigned r = 0; r < b.rows; ++r)
        for (unsigned c = 0; c < b.width; ++c) {
          const double a = b.buffer[r * unsigned(b.pitch) + c] / 255.0;
          if (a <= 0) continue;
          const int px = x + pen + g->bitmap_left + int(c), py = y - g->bitmap_top + int(r);
          img->fill_rect(px, py, px + 1, py + 1, rgb, a);
        }
    }
    pen += int(g->advance.x >> 6);
  }
  return pen;
}

}  // namespace

int draw_text(RgbImage& img, int x, int y, const std::string& text, int size_px, const uint8_t rgb[3]) {
  return layout(&img, x, y, text, size_px, rgb);
}

int text_width(const std::string& text, int size_px) { return layout(nullptr, 0, 0, text, size_px, nullptr); }

}  // namespace fploc
