// The IMU's part of the segmenter's roll/pitch (issue 11 item 3): GravityFusion (gravity vs the planes' up:
// slopes, gyro prediction without planes) and the attitude moved from mid-sweep to the scan's time with the
// gyro (threshold jolts last less than a sweep: the pose at the scan's time must not carry mid-sweep's tilt).
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "fploc/segmentation/segmenter.h"
#include "segmenter_constants.h"

namespace fploc::seg {

void Segmenter::fuse_imu(const Scan& scan, const Eigen::Vector3d& plane_up) {
  if (!cfg_.imu_attitude || !fusion_.has_gyro()) return;
  const int64_t tm = scan.utime + std::llround(out_.attitude_t * 1e6);
  const bool plane = out_.attitude_source == AttitudeSource::kCeiling || out_.attitude_source == AttitudeSource::kGround;
  // The plane taken is last scan's as it was (the fit kept its start, prev_*_ not yet replaced by this scan's).
  const bool repeated =
      (out_.attitude_source == AttitudeSource::kCeiling && have_prev_ceiling_ && out_.ceiling.coeffs == prev_ceiling_) ||
      (out_.attitude_source == AttitudeSource::kGround && have_prev_ground_ && out_.ground.coeffs == prev_ground_);
  const GravityFusion::Result r = fusion_.update(tm, plane ? &plane_up : nullptr, out_.roll_pitch_sigma,
                                                 accel_this_scan_ ? &accel_mean_ : nullptr, deskew_.bias(), repeated);
  if (!r.text.empty()) out_.note(r.text);
  if (!r.valid || r.from_planes) return;  // level: the planes' attitude as it is
  roll_pitch_from_up(r.up, out_.roll, out_.pitch);
  out_.roll_pitch_sigma = r.sigma;
  char buf[160];
  if (r.held) {
    out_.attitude_source = AttitudeSource::kPrevious;
    std::snprintf(buf, sizeof buf, "attitude: the last gravity held (sigma %.2f deg)", r.sigma / k::kDeg);
  } else if (r.predicted) {
    out_.attitude_source = AttitudeSource::kGyro;
    std::snprintf(buf, sizeof buf, "attitude: no plane, gravity carried by the gyro (sigma %.2f deg)", r.sigma / k::kDeg);
  } else if (r.settling) {
    out_.attitude_source = AttitudeSource::kSlope;
    std::snprintf(buf, sizeof buf, "attitude: level again, the planes blended in with the gyro (sigma %.2f deg)", r.sigma / k::kDeg);
  } else {
    out_.attitude_source = AttitudeSource::kSlope;
    std::snprintf(buf, sizeof buf, "attitude: planes + surface slope %.2f deg (gyro/IMU gravity)", fusion_.slope_deg());
  }
  out_.note(buf);
}

void Segmenter::attitude_to_scan_time(const Scan& scan) {
  // roll/pitch at mid-sweep -> at utime (the pose's time) with the gyro. The wall points stay as they are
  // (raw, with their times: downstream compensates the motion per point).
  if (!cfg_.imu_attitude || out_.attitude_t == 0 || !fusion_.has_gyro()) return;
  if (out_.attitude_source == AttitudeSource::kNone) return;
  const int64_t tm = scan.utime + std::llround(out_.attitude_t * 1e6);
  Eigen::Matrix3d R;
  if (!fusion_.rotation(tm, scan.utime, deskew_.bias(), &R)) return;
  const Eigen::Vector3d up_m = up_from_roll_pitch(out_.roll, out_.pitch);
  const Eigen::Vector3d up_u = (R.transpose() * up_m).normalized();
  double roll_u, pitch_u;
  roll_pitch_from_up(up_u, roll_u, pitch_u);
  out_.roll = roll_u;
  out_.pitch = pitch_u;
  // z: measured at mid-sweep; at utime it is interpolated between the last scan's mid-sweep z and this one
  // (what downstream did with attitude_t before: the gyro says nothing about height).
  const bool z_known = out_.z_source == HeightSource::kCeiling || out_.z_source == HeightSource::kGround;
  const double z_mid = out_.z;
  if (z_known && have_prev_mid_z_ && tm > prev_mid_t_ && scan.utime >= prev_mid_t_ && tm - prev_mid_t_ < 1000000) {
    const double s = double(scan.utime - prev_mid_t_) / double(tm - prev_mid_t_);
    out_.z = prev_mid_z_ + s * (z_mid - prev_mid_z_);
  }
  if (z_known) {
    have_prev_mid_z_ = true;
    prev_mid_t_ = tm;
    prev_mid_z_ = z_mid;
  }
  out_.attitude_t = 0;  // roll/pitch/z now at utime
}

}  // namespace fploc::seg
