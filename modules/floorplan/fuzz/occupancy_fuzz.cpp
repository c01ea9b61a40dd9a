// libFuzzer target for occupancy maps (ROS map_server YAML + PGM): the input is split at the first
// "\n---pgm---\n" into the YAML text and the PGM bytes; both must parse or throw std::runtime_error, and
// a parsed map is converted and vectorised.
// Build: CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DFPLOC_FUZZ=ON && ninja -C build-fuzz occupancy_fuzz
// Run:   build-fuzz/bin/occupancy_fuzz -max_total_time=180 CORPUS_DIR
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fploc/floorplan/occupancy.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  const std::string sep = "\n---pgm---\n";
  const auto k = all.find(sep);
  const std::string yaml = k == std::string::npos ? all : all.substr(0, k);
  const std::string pgm = k == std::string::npos ? std::string() : all.substr(k + sep.size());
  try {
    const auto y = fploc::parse_map_yaml(yaml, "fuzz.yaml");
    if (pgm.empty()) return 0;
    const auto img = fploc::read_pgm(pgm, "fuzz.pgm");
    if (size_t(img.width) * size_t(img.height) > (1u << 20)) return 0;  // keep runs fast
    const auto g = fploc::occupancy_from_image(img, y, "fuzz.pgm");
    fploc::VectoriseStats st;
    (void)fploc::vectorise_occupancy(g, {}, &st);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
