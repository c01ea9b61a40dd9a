// scan_t <-> Scan (OS-1 range image and its intrinsics). Pure mappings.
#pragma once
#include <fploc/scan_t.hpp>

#include "fploc/core/scan.h"

namespace fploc::adapters {

void to_msg(const Scan& s, scan_t& m);
// Throws std::runtime_error naming the field when the message is inconsistent (sizes, beam count).
void from_msg(const scan_t& m, Scan& s);

}  // namespace fploc::adapters
