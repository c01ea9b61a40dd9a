#include "fploc/sim/beam_patterns.h"

#include <filesystem>
#include <stdexcept>

#include "fploc/sim/sensor.h"

namespace fploc::sim {

const std::vector<std::string>& beam_pattern_names() {
  static const std::vector<std::string> names = {"os1-64", "os1-32", "os1-128", "vlp16"};
  return names;
}

BeamIntrinsics nominal_ouster(int beams, double fov) {
  BeamIntrinsics b;
  const double az[4] = {3.1, 0.9, -1.3, -3.4};
  const int shift[4] = {19, 13, 6, 0};
  for (int u = 0; u < beams; ++u) {
    b.altitude_deg.push_back(fov / 2 - u * (fov / (beams - 1)));
    b.azimuth_deg.push_back(az[u % 4]);
    b.pixel_shift_by_row.push_back(shift[u % 4]);
  }
  b.beam_offset_mm = 12.163;
  return b;
}

BeamIntrinsics vlp16_like() {
  BeamIntrinsics b;
  for (int u = 0; u < 16; ++u) {
    b.altitude_deg.push_back(15.0 - 2.0 * u);
    b.azimuth_deg.push_back(0.0);
    b.pixel_shift_by_row.push_back(0);
  }
  b.beam_offset_mm = 0.0;
  return b;
}

namespace {
// A real sensor's metadata from ../shared (the beam angles, offsets and pixel shifts of that unit), else
// the generated pattern.
BeamIntrinsics from_shared(const std::string& shared_dir, const std::string& rel, int beams, double fov,
                           std::string* source) {
  const std::string p = shared_dir + "/data/ouster/" + rel;
  std::string err;
  BeamIntrinsics b;
  if (!shared_dir.empty() && std::filesystem::exists(p) && load_beam_intrinsics_json(p, b, &err) && b.beams() == beams) {
    if (source) *source = p;
    return b;
  }
  if (source)
    *source = "nominal OS-1-" + std::to_string(beams) + " (generated in code; " + (err.empty() ? p + " not found" : err) + ")";
  return nominal_ouster(beams, fov);
}
}  // namespace

BeamIntrinsics beam_pattern(const std::string& name, const std::string& shared_dir, std::string* source) {
  if (name == "os1-64" || name.empty()) {
    std::string src;
    BeamIntrinsics b = default_beams(shared_dir, &src);
    if (source) *source = src;
    return b;
  }
  if (name == "os1-32") return from_shared(shared_dir, "OS-1-32-G_v2.1.1_1024x10.json", 32, 33.2, source);
  if (name == "os1-128") return from_shared(shared_dir, "OS-1-128_v2.3.0_1024x10.json", 128, 45.0, source);
  if (name == "vlp16") {
    if (source) *source = "VLP-16-like (generated in code: 16 beams, -15..+15 deg)";
    return vlp16_like();
  }
  std::string all;
  for (const auto& n : beam_pattern_names()) all += (all.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown beam pattern '" + name + "' (one of: " + all + ")");
}

}  // namespace fploc::sim
