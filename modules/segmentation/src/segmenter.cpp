// Segmenter::process: one scan through preparation, the ceiling and ground fits, their acceptance, the
// attitude/height estimate and wall selection (see segmenter.h for the files of each step).
#include "fploc/segmentation/segmenter.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "segmenter_constants.h"

namespace fploc::seg {

const char* to_string(SegStatus s) {
  switch (s) {
    case SegStatus::kOk: return "OK";
    case SegStatus::kNoCeiling: return "NO_CEILING";
    case SegStatus::kBadInput: return "BAD_INPUT";
    case SegStatus::kEmpty: return "EMPTY";
  }
  return "?";
}

Eigen::Vector3d up_from_roll_pitch(double roll, double pitch) {
  // up_sensor = R^T e_z with R = Rz(yaw) Ry(pitch) Rx(roll).
  return {-std::sin(pitch), std::sin(roll) * std::cos(pitch), std::cos(roll) * std::cos(pitch)};
}

void roll_pitch_from_up(const Eigen::Vector3d& u, double& roll, double& pitch) {
  roll = std::atan2(u.y(), u.z());
  pitch = std::atan2(-u.x(), std::hypot(u.y(), u.z()));
}

Segmenter::Segmenter(SegmenterConfig cfg, std::unique_ptr<PlaneFit> fit)
    : cfg_(cfg), fit_(std::move(fit)), deskew_(cfg.deskew_gyro), height_(cfg) {}
Segmenter::~Segmenter() = default;

void Segmenter::reset() {
  fit_->reset();
  deskew_ = GyroDeskew(cfg_.deskew_gyro);
  fusion_ = GravityFusion();
  height_.reset();
  {  // the last output as a new segmenter's, its arrays' capacity kept
    WallPoints wall = std::move(out_.wall);
    std::vector<uint8_t> label = std::move(out_.label);
    std::string text = std::move(out_.status_text);
    wall.clear();
    label.clear();
    text.clear();
    out_ = Segmentation{};
    out_.wall = std::move(wall);
    out_.label = std::move(label);
    out_.status_text = std::move(text);
  }
  have_prev_ceiling_ = have_prev_ground_ = false;
  prev_ceiling_.setZero();
  prev_ground_.setZero();
  follow_up_ = Eigen::Vector3d::UnitZ();
  follow_t_ = 0;
  follow_ = FollowRate{};
  kink_quiet_left_ = 0;
  kink_skew_per_rate_ = 0;
  kink_d_offset_ = 0;
  kink_skipped_ = 0;
  kink_armed_ = false;
  kink_thinned_ = 0;
  accel_sum_.setZero();
  accel_sq_ = 0;
  accel_n_ = 0;
  imu_trusted_ = false;
  imu_up_ = Eigen::Vector3d::UnitZ();
  have_imu_ = false;
  have_prev_mid_z_ = false;
  prev_mid_t_ = 0;
  prev_mid_z_ = 0;
  accel_this_scan_ = false;
  accel_mean_.setZero();
  // Kept: what depends only on the beam pattern and the configuration (lut_ and what is built with it in
  // prepare(): ring_order_, scale_, lut_soa_, row_z_, row_set_, row_ring_), and every per-scan scratch array
  // (written before it is read on each scan).
}

void Segmenter::add_accel(const Eigen::Vector3d& a) {
  if (!a.allFinite() || a.norm() < 1.0) return;
  accel_sum_ += a;
  accel_sq_ += a.squaredNorm();
  ++accel_n_;
}

double Segmenter::mid_sweep_offset(const Scan& scan) {
  // Halfway between the first and the last valid column time (0 without column times).
  const bool cvalid = scan.column_valid.size() == scan.column_utime.size();
  int64_t t0 = 0, t1 = 0;
  for (size_t c = 0; c < scan.column_utime.size(); ++c) {
    const int64_t t = scan.column_utime[c];
    if (t == 0 || (cvalid && !scan.column_valid[c])) continue;
    if (t0 == 0 || t < t0) t0 = t;
    t1 = std::max(t1, t);
  }
  return t0 == 0 ? 0.0 : 1e-6 * double(t0 + (t1 - t0) / 2 - scan.utime);
}

void Segmenter::fit_ceiling(const Eigen::Vector3d& init_up, const Eigen::Vector3d& gate_up) {
  Eigen::Vector4d pl;
  std::string why;
  const double max_tilt = cfg_.max_tilt_deg * k::kDeg;
  if (!fit_->fit(upper_, init_up, have_prev_ceiling_ ? &prev_ceiling_ : nullptr, PlaneRole::kCeiling, pl)) {
    why = "no plane fit on the upper rings";
  } else {
    out_.ceiling.coeffs = pl;
    quality(upper_, out_.ceiling);
    const double tilt = std::acos(std::clamp(-pl.head<3>().dot(gate_up), -1.0, 1.0));
    if (tilt > max_tilt)
      why = "ceiling tilted " + std::to_string(tilt / k::kDeg) + " deg > max_tilt_deg";
    else if (pl[3] < k::kMinCeilingDistM)
      why = "ceiling plane not above the sensor";
    else if (out_.ceiling.inliers < scale_.min_plane_inliers)
      why = "ceiling has " + std::to_string(out_.ceiling.inliers) + " inliers < " +
            std::to_string(scale_.min_plane_inliers);
    else if (out_.ceiling.beyond > cfg_.max_beyond_ratio * out_.ceiling.inliers)
      why = "ceiling not where the rays end: " + std::to_string(out_.ceiling.beyond) + " returns beyond it vs " +
            std::to_string(out_.ceiling.inliers) + " inliers";
    else if (out_.ceiling.inliers < scale_.min_inlier_fraction * double(upper_.size()))
      why = "ceiling inliers are only " + std::to_string(100.0 * out_.ceiling.inliers / upper_.size()) +
            " % of the upper-ring returns";
  }
  out_.ceiling.found = why.empty();
  if (!why.empty()) {
    out_.status = SegStatus::kNoCeiling;
    out_.status_text = why;
  }
}

void Segmenter::fit_ground(const Eigen::Vector3d& up, bool from_previous) {
  // The same fit on the lower rings, flipped.
  Eigen::Vector4d pl;
  if (!fit_->fit(lower_, -up, have_prev_ground_ && from_previous ? &prev_ground_ : nullptr, PlaneRole::kGround, pl))
    return;
  out_.ground.coeffs = pl;
  quality(lower_, out_.ground);
  const double tilt = std::acos(std::clamp(pl.head<3>().dot(up), -1.0, 1.0));
  out_.ground.found = tilt < std::min(cfg_.max_tilt_deg * k::kDeg, k::kMaxGroundTiltDeg * k::kDeg) &&
                      pl[3] > k::kMinGroundDistM && out_.ground.inliers >= scale_.min_plane_inliers &&
                      out_.ground.beyond <= cfg_.max_beyond_ratio * out_.ground.inliers;
}

void Segmenter::refit_ground_around_gravity(int64_t t) {
  // Off a slope (a ramp's head, a landing) without an IMU prior the ground is searched around the last
  // attitude, the slope's, and started from the last ground, the slope's: a level floor lies outside that
  // gate, or loses the start. No ground, so the fusion keeps the slope and can take a sloped ceiling ahead
  // for the surface (40 s at 8.5 deg in the demo building's lobby, z from that ceiling 10-16 cm off).
  // Floors are level more often: when no ground was found, search around gravity as the gyro carries it.
  Eigen::Vector3d g;
  if (out_.ground.found || !fusion_.gravity_up_at(t, deskew_.bias(), &g)) return;
  const Plane kept = out_.ground;
  fit_ground(g, false);  // not started from the last ground (the slope's): it would win the start again
  // At a ramp's head the ramp behind is below the landing: its returns count as "beyond" the level plane,
  // often more than the usual share. Level within 1 deg of gravity with most returns on it is the floor;
  // the kink split (ground_kink.cpp) then sees the two surfaces.
  Plane& gr = out_.ground;
  const bool level = std::acos(std::clamp(gr.coeffs.head<3>().dot(g), -1.0, 1.0)) < k::kRefitLevelDeg * k::kDeg;
  if (!gr.found && level && gr.coeffs[3] > k::kMinGroundDistM && gr.inliers >= scale_.min_plane_inliers &&
      gr.beyond < gr.inliers)
    gr.found = true;
  if (!gr.found) {
    gr = kept;
    return;
  }
  out_.note("ground: none around the prior, a level one around gravity (" + std::to_string(gr.beyond) +
            " returns below it)");
}

const Segmentation& Segmenter::process(const Scan& scan) {
  out_.utime = scan.utime;
  out_.attitude_t = mid_sweep_offset(scan);
  out_.seq = scan.seq;
  out_.status = SegStatus::kOk;
  out_.status_text.clear();
  out_.ceiling = Plane{};
  out_.ground = Plane{};
  out_.label.clear();  // (the wall points are rewritten by select_walls, cleared on the early returns)

  // Gravity prior: IMU (when enabled and available), else the sensor's z axis.
  accel_this_scan_ = false;
  if (accel_n_ > 0) {
    const Eigen::Vector3d mean = accel_sum_ / accel_n_;
    imu_up_ = mean.normalized();
    have_imu_ = true;
    // Gravity alone: the mean's magnitude is g and the samples scatter little around it (no jolt).
    const double spread = std::sqrt(std::max(0.0, accel_sq_ / accel_n_ - mean.squaredNorm()));
    imu_trusted_ = std::abs(mean.norm() - k::kGravityMs2) < k::kImuTrustNormTolMs2 && spread < k::kImuTrustSpreadMs2;
    accel_mean_ = mean;
    accel_this_scan_ = true;
    accel_sum_.setZero();
    accel_sq_ = 0;
    accel_n_ = 0;
  }
  ImuPrior imu;
  imu.valid = cfg_.use_imu_prior && have_imu_;
  imu.up = imu_up_;
  imu.trusted = imu.valid && imu_trusted_;
  const Eigen::Vector3d gate_up = imu.valid ? imu_up_ : Eigen::Vector3d::UnitZ();

  if (!prepare(scan)) {
    out_.wall.clear();
    height_.hold(out_, imu);
    return out_;
  }
  if (scan.status == ScanStatus::kBadInput) {
    out_.status = SegStatus::kBadInput;
    out_.status_text = "scan marked bad by the driver";
    out_.wall.clear();
    height_.hold(out_, imu);
    return out_;
  }
  if (keep_labels_) out_.label.assign(size_t(scan.height) * scan.width, 0);
  if (fit_->reads_points()) {  // Candidates::p for fits that read it (RANSAC)
    upper_.fill_points();
    lower_.fill_points();
  }

  // Prior up: the IMU's gravity, else the last measured attitude (the ceiling's up in the paper's case; the
  // ground's when the ceiling over the sensor was not level), else the sensor's z axis.
  const Eigen::Vector3d init_up = imu.valid ? imu_up_ : (height_.has_up() ? height_.last_up() : gate_up);
  fit_ceiling(init_up, gate_up);
  const Eigen::Vector3d up =
      out_.ceiling.found ? Eigen::Vector3d(-out_.ceiling.coeffs.head<3>()) : init_up.normalized();
  // The ground is fitted around the ceiling's up when the ceiling agrees with the prior (the paper's case),
  // else around the prior: a sloped ceiling patch taken as the ceiling must not drag the floor's gate along.
  const double ceiling_vs_prior = std::acos(std::clamp(up.dot(init_up.normalized()), -1.0, 1.0));
  fit_ground(ceiling_vs_prior < k::kCeilingPriorAgreeDeg * k::kDeg ? up : init_up.normalized());
  const int64_t t_mid = scan.utime + std::llround(out_.attitude_t * 1e6);
  refit_ground_around_gravity(t_mid);
  split_ground_at_kink(t_mid, scan);

  if (height_.has_areas() && upper_.p.size() != upper_.size()) upper_.fill_points();  // the area census reads p
  const Eigen::Vector3d plane_up = height_.update(out_, imu, &upper_);
  fuse_imu(scan, plane_up);
  if (out_.ceiling.found) {
    have_prev_ceiling_ = true;
    prev_ceiling_ = out_.ceiling.coeffs;
    deskew_.update_bias(up);
  } else {
    deskew_.forget_up();
  }
  if (out_.ground.found) {
    have_prev_ground_ = true;
    prev_ground_ = out_.ground.coeffs;
  }

  select_walls(scan, up);
  attitude_to_scan_time(scan);
  return out_;
}

}  // namespace fploc::seg
