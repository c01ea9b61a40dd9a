#include "fploc/localizer/localizer.h"

#include "fploc/matcher/free_space_check.h"

#include <algorithm>
#include <cmath>

namespace fploc::localizer {

namespace {
Config with_uncertainty_defaults(Config c) {
  // The frame covariance is of the matcher's estimate: its loss and final gate.
  c.uncertainty.frame.loss = c.matcher.loss;
  c.uncertainty.frame.loss_scale_m = c.matcher.loss_scale_m;
  c.uncertainty.frame.gate_m = c.matcher.min_correspondence_m;
  c.uncertainty.frame.group_rule = c.matcher.group_rule;
  // The odometry's error model is the matcher's (its window and the tracker's prediction agree).
  c.uncertainty.odom_sigma_m = c.matcher.odom_sigma_m;
  c.uncertainty.odom_sigma_per_m = c.matcher.odom_sigma_per_m;
  c.uncertainty.odom_sigma_rad = c.matcher.odom_sigma_rad;
  c.uncertainty.odom_sigma_per_rad = c.matcher.odom_sigma_per_rad;
  c.uncertainty.odom_sigma_rad_per_m = c.matcher.odom_sigma_rad_per_m;
  // The as-built model's loss on element offsets bounds what a wall far off pulls (the optimizer node's
  // config carries it in the optimizer's, the matcher node's in the matcher's).
  if (c.uncertainty.frame.element_loss_scale_m == 0) {
    const matcher::AsBuiltModel& ab = c.optimizer.as_built.on() ? c.optimizer.as_built : c.matcher.as_built;
    if (ab.on() && ab.loss_scale_m > 0) c.uncertainty.frame.element_loss_scale_m = ab.loss_scale_m;
  }
  // The window publishes POOR where its pose's covariance (the fix's + the offset from it) says what the
  // tracker's status says for the fix's.
  if (c.uncertainty.enabled && c.optimizer.poor_sigma_m <= 0) c.optimizer.poor_sigma_m = c.uncertainty.poor_sigma_m;
  return c;
}
}  // namespace

void use_map(Config& cfg, const matcher::LocalizationMap& map) {
  cfg.free_space = map.free_space.get();
  cfg.map_sigma_m = map.map_sigma_m;
}

Localizer::Localizer(const matcher::NearestLookup& lookup, Config cfg)
    : cfg_(with_uncertainty_defaults(std::move(cfg))),
      lookup_(lookup),
      matcher_(lookup, cfg_.matcher),
      window_(lookup, cfg_.optimizer),
      tracker_(cfg_.uncertainty) {}

void Localizer::add_imu(int64_t utime, double gyro_z) {
  if (cfg_.use_imu) imu_.add(utime, gyro_z);
}

void Localizer::add_odometry(int64_t utime, const Pose2& p) {
  odom_[utime] = p;
  while (odom_.size() > 256) odom_.erase(odom_.begin());
}

void Localizer::set_pose(const Pose2& p, std::optional<double> search_m) {
  if (!search_m && cfg_.initial_search_m > 0) search_m = cfg_.initial_search_m;
  matcher_.set_pose(p, search_m);
  // The search region as a 3-sigma bound of the initial pose.
  const double sm = search_m && *search_m > 0 ? *search_m : cfg_.matcher.max_correspondence_m;
  tracker_.reset(sm / 3, cfg_.matcher.initial_search_yaw_rad / 3);
}

FramePose Localizer::register_frame(const FeatureFrame& f) {
  held_ = f;
  // Roll/pitch/z the segmenter could not estimate: the last known ones.
  if (z_known(f)) last_z_ = f.z;
  else if (last_z_) held_.z = *last_z_;
  if (roll_pitch_known(f)) last_rp_ = {f.roll, f.pitch};
  else if (last_rp_) held_.roll = last_rp_->first, held_.pitch = last_rp_->second;
  std::optional<double> dyaw;
  if (cfg_.use_imu) {
    // Prediction: the yaw change since the previous frame; motion compensation: the mean rate over
    // this frame's sweep (its samples arrive before the scan is complete).
    if (have_prev_) dyaw = imu_.integral(prev_utime_, f.utime);
    const double sweep = matcher::sweep_duration(f);
    if (sweep > 0)
      if (auto w = imu_.mean_rate(f.utime, f.utime + std::llround(sweep * 1e6))) held_.sweep_yaw_rate = *w;
    imu_.drop_before(std::min(f.utime, have_prev_ ? prev_utime_ : f.utime));
  }
  const std::optional<Pose2> motion = have_prev_ ? odometry_between(prev_utime_, f.utime) : std::nullopt;
  FramePose out;
  out.utime = f.utime;
  out.scan_seq = f.scan_seq;
  out.match = matcher_.process(held_, dyaw, motion);
  if (out.match.status != matcher::FitStatus::kNotInitialised) {
    prev_utime_ = f.utime;
    have_prev_ = true;
  }
  out.roll = held_.roll;
  out.pitch = held_.pitch;
  out.z = held_.z;
  out.roll_pitch_sigma = f.roll_pitch_sigma;
  out.z_sigma = f.z_sigma;
  return out;
}

std::optional<Pose2> Localizer::odometry_at(int64_t utime) const {
  auto hi = odom_.lower_bound(utime);  // the first sample at or after utime
  if (hi != odom_.end() && hi->first == utime) return hi->second;
  if (hi == odom_.begin()) return std::nullopt;  // every sample is newer
  const auto lo = std::prev(hi);
  if (hi == odom_.end())  // the newest sample is older: it stands for utime while recent
    return double(utime - lo->first) * 1e-6 <= cfg_.odometry_max_age_s ? std::optional<Pose2>(lo->second) : std::nullopt;
  // Between two samples: the increment from the older one, scaled linearly in time.
  return interpolate(lo->second, hi->second, double(utime - lo->first) / double(hi->first - lo->first));
}

std::optional<Pose2> Localizer::odometry_between(int64_t from_utime, int64_t to_utime) const {
  const auto a = odometry_at(from_utime), b = odometry_at(to_utime);
  if (!a || !b) return std::nullopt;
  return between(*a, *b);
}

double Localizer::contradicted(const FeatureFrame& f, const Pose2& x, double inlier_ratio) const {
  return cfg_.free_space ? matcher::contradicted_share(*cfg_.free_space, f, x, cfg_.matcher.inlier_m, inlier_ratio) : 0.0;
}

std::optional<Pose> Localizer::optimize(const FeatureFrame& f, const FramePose& sfr, std::vector<Pose>* finals) {
  if (sfr.match.status == matcher::FitStatus::kNotInitialised) return std::nullopt;
  // The odometry's increment since the previous optimized frame predicts this one in the tracker, as in the
  // matcher (in the optimizer node the odometry arrives on its own `odom` input).
  const std::optional<Pose2> motion = have_prev_optimized_ ? odometry_between(prev_optimized_utime_, f.utime) : std::nullopt;
  prev_optimized_utime_ = f.utime;
  have_prev_optimized_ = true;
  optimizer::FrameInput in;
  in.features = f;
  in.sfr = sfr.match.pose;
  in.twist = sfr.match.twist;
  in.status = sfr.match.status;
  in.covariance = sfr.match.covariance;
  in.published_status = sfr.match.status;
  in.status_text = sfr.match.text;
  if (cfg_.uncertainty.enabled) {
    // The frame de-skewed to its mean point time with the matcher's twist, at the pose of that time (as
    // the window's keyframes; FramePose from a message carries only the pose at utime and the twist).
    const double t_ref = matcher::mean_time(f);
    matcher::deskew(f, sfr.match.twist, t_ref, &deskewed_);
    const Pose2 at_ref = compose(sfr.match.pose, matcher::exp_twist(sfr.match.twist, t_ref));
    const auto fu = optimizer::frame_uncertainty(lookup_, deskewed_, at_ref, cfg_.uncertainty.frame);
    uncertainty_ = tracker_.update(f.utime, fu.covariance, fu.valid, sfr.match.status, sfr.match.text, &sfr.match.pose,
                                   &sfr.match.twist, sfr.match.fit.inlier_ratio, motion ? &*motion : nullptr,
                                   contradicted(deskewed_, at_ref, sfr.match.fit.inlier_ratio));
    in.covariance = uncertainty_.covariance;
    in.published_status = uncertainty_.status;
    in.status_text = uncertainty_.text;
  }
  add_map_error(f, &in.covariance);
  return window_.add(std::move(in), finals);
}

void Localizer::add_map_error(const FeatureFrame& f, Eigen::Matrix3d* covariance) {
  if (!(cfg_.map_sigma_m > 0) || f.points.empty()) return;
  ranges_.clear();
  for (const auto& p : f.points) ranges_.push_back(p.p.norm());
  const auto mid = ranges_.begin() + std::ptrdiff_t(ranges_.size() / 2);
  std::nth_element(ranges_.begin(), mid, ranges_.end());
  const double sxy = cfg_.map_sigma_m, syaw = sxy / std::max(*mid, 1.0);
  *covariance += Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
}

Localizer::Step Localizer::process(const FeatureFrame& f, std::vector<Pose>* finals) {
  Step s;
  s.sfr = register_frame(f);
  s.latest = optimize(f, s.sfr, finals);
  if (s.latest && cfg_.refine_from_window) refine(s.latest->utime, s.latest->pose);
  return s;
}

}  // namespace fploc::localizer
