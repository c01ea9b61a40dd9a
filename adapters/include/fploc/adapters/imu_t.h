// imu_t from an IMU sample (SI units, the OS-1's or another source's). Pure mapping.
#pragma once
#include <fploc/imu_t.hpp>

#include <string>

#include "fploc/os1/packet.h"

namespace fploc::adapters {

// utime = the accelerometer's time stamp; `source` names the IMU ("os1", "xsens", ...).
imu_t to_msg(const os1::ImuSample& s, int64_t seq, const std::string& source);

}  // namespace fploc::adapters
