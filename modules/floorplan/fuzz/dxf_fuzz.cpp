// libFuzzer target for the DXF reader: any input must either load or throw std::runtime_error.
// Build: CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DFPLOC_FUZZ=ON && ninja -C build-fuzz dxf_fuzz
// Run:   build-fuzz/bin/dxf_fuzz -max_total_time=600 -dict=modules/floorplan/fuzz/dxf.dict CORPUS_DIR
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fploc/floorplan/dxf.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fploc::PlanLoadOptions o;
  o.quiet = true;
  o.curve_tolerance = 0.05;
  try {
    auto plan = fploc::read_plan_dxf(text, "fuzz.dxf", o);
    for (const auto& e : plan.elements) (void)fploc::distance(e, Eigen::Vector2d(0.5, 0.5));
  } catch (const std::runtime_error&) {
  }
  return 0;
}
