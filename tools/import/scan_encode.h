// scan_t's LCM encoding written straight from a Scan: the same bytes as to_msg() + scan_t::encode()
// (checked by scan_encode_test), without the intermediate message and LCM's per-element array
// encoders, which were a fifth of an import's CPU time.
#pragma once
#include <cstdint>
#include <vector>

#include "fploc/core/scan.h"

namespace fploc::import {

// Replaces out with the encoded scan_t (fingerprint included).
void encode_scan(const Scan& s, std::vector<uint8_t>& out);

}  // namespace fploc::import
