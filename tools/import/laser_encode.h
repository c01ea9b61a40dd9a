// sensor_msgs/LaserScan -> laser_scan_t, encoded in one pass from the recording's bytes into the log's
// buffer: the same bytes as filling a laser_scan_t and calling its encode(), without the two float
// vectors, the message and the scratch buffer in between (LCM's encoder also swaps one float at a time;
// here the arrays are byte-swapped in vector registers, or copied as they are from big-endian CDR).
#pragma once
#include <cstddef>
#include <cstdint>

#include "fploc/recording/ros_msgs.h"

namespace fploc::import {

// laser_scan_t's encoded size for this scan (utime = the header stamp in us, frame = its frame id).
size_t laser_scan_encoded_size(const rec::LaserScanView& l);
// Writes exactly laser_scan_encoded_size(l) bytes at out.
void encode_laser_scan(const rec::LaserScanView& l, uint8_t* out);

}  // namespace fploc::import
