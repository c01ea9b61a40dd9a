// Beam patterns of spinning LiDARs the simulator can emit (issue 13 item 2): the Ouster ones from real
// sensor metadata in ../shared when present (else a nominal pattern generated in code), and a
// VLP-16-like pattern (16 beams, -15..+15 deg every 2 deg, one firing azimuth, no beam offset).
#pragma once
#include <string>
#include <vector>

#include "fploc/core/scan.h"

namespace fploc::sim {

// The names `--beams` accepts: os1-64 (the default), os1-32, os1-128, vlp16.
const std::vector<std::string>& beam_pattern_names();

// The beams of pattern `name`. `source` says where they came from (a metadata file or "generated").
// Throws std::invalid_argument naming the pattern and the accepted names for an unknown name.
BeamIntrinsics beam_pattern(const std::string& name, const std::string& shared_dir, std::string* source);

// Nominal uniform Ouster pattern (no shared metadata): `beams` altitudes from +fov/2 to -fov/2, the
// four-fold azimuth stagger (+3.1/+0.9/-1.3/-3.4 deg) and its pixel shifts for 1024 columns.
BeamIntrinsics nominal_ouster(int beams, double vertical_fov_deg);

// VLP-16-like: 16 beams at -15..+15 deg (2 deg apart), all at azimuth 0, no offsets or pixel shifts.
BeamIntrinsics vlp16_like();

}  // namespace fploc::sim
