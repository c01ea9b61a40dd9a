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
// The same bytes written at out (encoded_scan_size(s) of them), e.g. into the log's buffer
// (LcmLog::begin_event): no scratch buffer and no copy.
size_t encoded_scan_size(const Scan& s);
void encode_scan(const Scan& s, uint8_t* out);

}  // namespace fploc::import
