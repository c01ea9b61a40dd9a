// Gyro de-skew of one LiDAR sweep: the rotation of every column's returns into the sensor frame at
// mid-sweep, integrated from the gyro (body frame = sensor frame), and the gyro bias (the part
// perpendicular to gravity) estimated from consecutive ceilings. Transport-free.
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

#include "fploc/core/scan.h"

namespace fploc::seg {

class GyroDeskew {
 public:
  explicit GyroDeskew(bool enabled) : enabled_(enabled) {}

  // Gyro sample (rad/s, sensor frame) at utime [us, the scan's clock]; bad or out-of-order samples ignored.
  void add(const Eigen::Vector3d& rate, int64_t utime);
  // Column rotations R_mid<-c for this sweep (rotation_at(), interleaved()). False when the scan is used as measured
  // (disabled, gyro not covering the sweep, no column times, or a rotation below 0.001 deg).
  bool prepare(const Scan& scan);
  // After a true prepare(): column c's rotation, and all of them as floats interleaved by groups of eight
  // columns, entry (e / 3, e % 3) of column c at interleaved()[(c / 8) * 72 + e * 8 + c % 8] (the layout the
  // segmenter's eight-lane point preparation loads; room for the width rounded up to eight).
  Eigen::Matrix3f rotation_at(int c) const;
  const float* interleaved() const { return rot_il_.data(); }
  // Where column c's entry (0, 0) lies in interleaved() (entry e at + e * 8).
  static size_t interleaved_offset(int c) { return size_t(c / 8) * 72 + size_t(c % 8); }
  // After prepare(): this sweep's mid-sweep time when the gyro covers it, else 0.
  int64_t sweep_mid_utime() const { return sweep_tm_; }
  // Up vector (sensor frame) of the ceiling found at mid-sweep: refines the bias. forget_up() when none.
  void update_bias(const Eigen::Vector3d& up);
  void forget_up() { have_bias_ref_ = false; }
  const Eigen::Vector3d& bias() const { return gyro_bias_; }

 private:
  Eigen::Vector3d rate_at(int64_t utime) const;
  // rate_at(utime) for a time in this sweep, from sweep_rate_ (the samples prepare() copied, the bias
  // subtracted once: the same values), searched from sample `at` on (a sweep's columns are walked in time
  // order: a step or two instead of a search); `at` is left at the sample taken.
  const Eigen::Vector3d& sweep_rate_walk(int64_t utime, size_t& at) const;
  bool covers(int64_t ta, int64_t tb) const;
  Eigen::Matrix3d rotation(int64_t ta, int64_t tb) const;

  bool enabled_;
  std::deque<std::pair<int64_t, Eigen::Vector3d>> gyro_;  // last ~1 s of samples, increasing time
  Eigen::Vector3d gyro_bias_ = Eigen::Vector3d::Zero();
  int64_t sweep_tm_ = 0;
  bool have_bias_ref_ = false;
  int64_t bias_ref_t_ = 0;
  Eigen::Vector3d bias_ref_up_ = Eigen::Vector3d::UnitZ();
  std::vector<int64_t> col_t_;
  std::vector<float> rot_il_;                                  // the column rotations (interleaved())
  std::vector<std::pair<int64_t, Eigen::Vector3d>> sweep_rate_;  // prepare(): this sweep's samples minus the bias
};

}  // namespace fploc::seg
