// libFuzzer target for the CARMEN log reader: any text must parse or throw std::runtime_error; a parsed
// log then goes through scan_times and (small) grid building.
// Build: CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DFPLOC_FUZZ=ON && ninja -C build-fuzz fuzz_carmen
// Run:   build-fuzz/bin/fuzz_carmen -max_total_time=180 CORPUS_DIR (seeds: lines of the Radish logs)
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fploc/carmen/carmen.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto log = fploc::carmen::parse_log(text, "fuzz.log");
    std::string note;
    (void)fploc::carmen::scan_times(log, &note);
    std::vector<const fploc::carmen::LaserRecord*> scans;
    for (const auto& s : log.scans)
      if (scans.size() < 4) scans.push_back(&s);
    fploc::carmen::GridConfig cfg;
    cfg.resolution = 0.25;
    cfg.max_free_m = 5;
    if (!scans.empty()) (void)fploc::carmen::build_grid(scans, cfg);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
