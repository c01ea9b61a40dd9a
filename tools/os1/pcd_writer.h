#pragma once
#include <string>

#include "fploc/core/scan.h"
#include "fploc/core/xyz.h"

// Writes one frame as an organized, destaggered PCL cloud (x y z intensity; NaN where no return).
// Returns "" or an error message.
std::string write_pcd(const fploc::Scan& scan, const fploc::XyzLut& lut, const std::string& path);
