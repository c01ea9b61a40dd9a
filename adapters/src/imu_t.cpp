#include "fploc/adapters/imu_t.h"

namespace fploc::adapters {

imu_t to_msg(const os1::ImuSample& s, int64_t seq, const std::string& source) {
  imu_t m;
  m.utime = int64_t(s.accel_ts_ns / 1000);
  m.accel_utime = int64_t(s.accel_ts_ns / 1000);
  m.gyro_utime = int64_t(s.gyro_ts_ns / 1000);
  m.seq = seq;
  for (int i = 0; i < 3; ++i) m.accel[i] = s.accel_mps2[i], m.gyro[i] = s.gyro_radps[i];
  m.source = source;
  return m;
}

}  // namespace fploc::adapters
