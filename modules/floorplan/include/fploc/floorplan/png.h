// Writing pictures of plans: an RGB image (row-major, 3 bytes per pixel) as a PNG file (libpng, which
// the floor-plan library already links to read occupancy maps).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fploc {

// Throws std::runtime_error naming `path` when it cannot be written or img.size() != w * h * 3.
void write_rgb_png(const std::string& path, int w, int h, const std::vector<uint8_t>& img);

}  // namespace fploc
