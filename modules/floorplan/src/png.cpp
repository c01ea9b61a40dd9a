#include "fploc/floorplan/png.h"

#include <png.h>

#include <cstdio>
#include <stdexcept>

namespace fploc {

void write_rgb_png(const std::string& path, int w, int h, const std::vector<uint8_t>& img) {
  if (w <= 0 || h <= 0 || img.size() != size_t(w) * size_t(h) * 3)
    throw std::runtime_error(path + ": image of " + std::to_string(img.size()) + " bytes is not " + std::to_string(w) +
                             " x " + std::to_string(h) + " RGB");
  FILE* fp = std::fopen(path.c_str(), "wb");
  if (!fp) throw std::runtime_error(path + ": cannot write");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(fp);
    throw std::runtime_error(path + ": PNG write error");
  }
  png_init_io(png, fp);
  png_set_IHDR(png, info, png_uint_32(w), png_uint_32(h), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int j = 0; j < h; ++j) png_write_row(png, &img[size_t(j) * size_t(w) * 3]);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(fp) != 0) throw std::runtime_error(path + ": write error");
}

}  // namespace fploc
