// Conversions between the transport-free core types and their LCM messages (shared by all nodes).
#pragma once
#include <fploc/imu_t.hpp>
#include <fploc/scan_t.hpp>

#include "fploc/core/scan.h"

namespace fploc {

void to_msg(const Scan& s, scan_t& m);
// Throws std::runtime_error naming the field when the message is inconsistent (sizes, beam count).
void from_msg(const scan_t& m, Scan& s);

}  // namespace fploc
