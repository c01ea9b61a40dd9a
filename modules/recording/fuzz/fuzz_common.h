// Shared by the bag and MCAP fuzzers: read every message of a recording and run every decoder on it
// (the one its type names and all the others: decoders must reject any bytes cleanly).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "fploc/recording/cloud_to_scan.h"
#include "fploc/recording/recording.h"
#include "fploc/recording/ros_msgs.h"

inline void fuzz_recording(const uint8_t* data, size_t size) {
  using namespace fploc::rec;
  std::string err;
  auto r = open_recording_memory(data, size, "fuzz", &err);
  if (!r) return;
  RawMessage m;
  int guard = 0;
  while (r->next(m) && ++guard < 20000) {
    const Connection& c = r->connections().at(m.conn);
    for (Encoding e : {c.encoding, c.encoding == Encoding::kCdr ? Encoding::kRos1 : Encoding::kCdr}) {
      PointCloud2 pc;
      if (decode(m.data, m.size, e, pc, &err)) {
        fploc::Scan s;
        CloudOptions o;
        o.rings = int(m.size % 3 == 0 ? m.size % 40 : 0);
        cloud_to_scan(pc, o, s, nullptr, &err);
      }
      Imu u;
      decode(m.data, m.size, e, u, &err);
      LaserScan l;
      decode(m.data, m.size, e, l, &err);
      Odometry od;
      decode(m.data, m.size, e, od, &err);
      std::vector<Transform> tf;
      decode_tf(m.data, m.size, e, tf, &err);
      const uint8_t* b;
      size_t n;
      decode_bytes(m.data, m.size, e, &b, &n, &err);
      std::string s;
      decode_string(m.data, m.size, e, s, &err);
    }
  }
}
