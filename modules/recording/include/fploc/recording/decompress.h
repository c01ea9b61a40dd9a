// Chunk decompression for bags (bz2, lz4) and MCAP (zstd, lz4): libbz2, liblz4 (frame format: roslz4
// and MCAP both write LZ4 frames) and libzstd. The expected size comes from the record; a mismatch or
// a decoder error is returned as text.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fploc::rec {

// Decompresses `in` (method "bz2", "lz4" or "zstd") into `out` (resized to `expected`). Returns "" or
// the reason it failed.
std::string decompress(const std::string& method, const uint8_t* in, size_t n, size_t expected,
                       std::vector<uint8_t>& out);

// The inverse, for tests and the benchmark's generated files.
std::vector<uint8_t> compress(const std::string& method, const uint8_t* in, size_t n);

}  // namespace fploc::rec
