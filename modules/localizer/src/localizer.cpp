#include "fploc/localizer/localizer.h"

#include "fploc/matcher/free_space_check.h"
#include "fploc/matcher/plan_terms.h"
#include "fploc/localizer/rival.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fploc::localizer {

namespace {

// The matcher's body twist at a fix as the plan-frame velocity (vx, vy, yaw rate) the odometry is set with.
Eigen::Vector3d plan_velocity(const matcher::MatchResult& m) {
  const double c = std::cos(m.pose.yaw), sn = std::sin(m.pose.yaw);
  return {c * m.twist.vx - sn * m.twist.vy, sn * m.twist.vx + c * m.twist.vy, m.twist.w};
}
Eigen::Matrix3d embed(const Eigen::Matrix2d& A) {  // x/y block, a tiny yaw variance (add_sigmas' basis)
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  M.topLeftCorner<2, 2>() = A;
  M(2, 2) = 1e-12;
  return M;
}

Config with_uncertainty_defaults(Config c) {
  // The frame covariance is of the matcher's estimate: its loss and final gate.
  c.uncertainty.frame.loss = c.matcher.loss;
  c.uncertainty.frame.loss_scale_m = c.matcher.loss_scale_m;
  c.uncertainty.frame.gate_m = c.matcher.min_correspondence_m;
  c.uncertainty.frame.group_rule = c.matcher.group_rule;
  // A second fit's structure counts from as many points as the matcher takes for a fit.
  if (c.uncertainty.rival_min_gained < 0) c.uncertainty.rival_min_gained = c.matcher.min_inliers;
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
  bool reseeded = false;  // this frame re-seeds a lost matcher (reseed_)
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
    const std::optional<DeadReckoned> dr = dead_reckoned(f, sfr);
    auto fu = optimizer::frame_uncertainty(lookup_, deskewed_, at_ref, cfg_.uncertainty.frame);
    const matcher::MatchResult* m = &sfr.match;
    Pose2 m_at_ref = at_ref;
    std::optional<Refit> refit;
    // (Not with the robot's own odometry: it predicts the frame, and the LiDAR odometry under the dead reckoning is the
    // weaker witness there. On the Radish logs' 2D scans, 1-2 s apart, it stood still for 10 m of corridor while the
    // wheels and the fixes moved on, and the refit from it, explaining more of the corridor's map, took the plan path
    // 9.5 m back.)
    const bool lost = sfr.match.status == matcher::FitStatus::kLost;
    if (dr && !motion && cfg_.uncertainty.dr_refit_ratio > 0 && (!lost || cfg_.uncertainty.dr_reseed_when_lost) &&
        (refit = refit_from_dead_reckoning(deskewed_, sfr, at_ref, fu.covariance, *dr, t_ref, lost))) {
      if (lost) {
        // A lost matcher's frame re-seeded: still LOST for the published status (the re-acquisition's confirmation
        // follows on the matcher's next fixes, as after a relocalizer's answer), in the window as a POOR frame at the
        // fit, and the matcher started again there with its tracking gate twice (the robot moves on a frame or two
        // before the pose reaches it).
        refit->match.text = "re-seeded from the dead reckoning";
        reseed_ = Reseed{f.utime, refit->match.pose, 2 * cfg_.matcher.gate_tracking_m};
        reseeded = true;
      }
      m = &refit->match;
      m_at_ref = refit->at_ref;
      fu = optimizer::frame_uncertainty(lookup_, deskewed_, m_at_ref, cfg_.uncertainty.frame);
      in.sfr = m->pose;  // (its status is the fix's; covariance and published status are the tracker's, below)
      if (lost) in.status = matcher::FitStatus::kPoor;  // (a re-seed: in the window as the other POOR frames)
    }
    uncertainty_ = tracker_.update(f.utime, fu.covariance, fu.valid, m->status, m->text, &m->pose, &m->twist,
                                   m->fit.inlier_ratio, motion ? &*motion : nullptr,
                                   contradicted(deskewed_, m_at_ref, m->fit.inlier_ratio), dr ? &*dr : nullptr);
    bool ambiguous = false;
    if (cfg_.uncertainty.rival_ratio > 0 && m->status == matcher::FitStatus::kOk &&
        (uncertainty_.confirming || have_rival_ || reacquiring_without_dr_))
      ambiguous = check_rival(deskewed_, m_at_ref, dr ? &*dr : nullptr, m->pose);
    if (reacquiring_without_dr_ && !ambiguous && !uncertainty_.confirming && m->status == matcher::FitStatus::kOk) {
      reacquiring_without_dr_ = false;  // no fit nearby explains more points than the fix: the stretch ends on it
      have_rival_ = false;
    }
    if (uncertainty_.status == matcher::FitStatus::kOk || m->status == matcher::FitStatus::kLost)
      have_rival_ = false;  // confirmed, or lost again: a new re-acquisition searches again
    // A weak fit that agrees with the dead reckoning in a stretch bounds the dead reckoning's claimed uncertainty
    // (UncertaintyConfig::dr_weak_fit_sigma): the frozen anchor moves to the dead-reckoned pose itself, with the tighter
    // of its covariance and the fix's plus their offset's second moment.
    if (cfg_.uncertainty.dr_weak_fit_sigma > 0 && uncertainty_.weak_fit && tracker_.wants_dead_reckoning() && dr &&
        have_frozen_ && dr_odometry_ && dr_last_utime_ == f.utime) {
      const Eigen::Vector3d d = pose_difference(m->pose, dr->pose);
      const Eigen::Matrix3d& fix_cov = uncertainty_.covariance;
      if (mahalanobis2(d, fix_cov + dr->covariance) <= chi2_3dof_of_sigmas(cfg_.uncertainty.dr_weak_fit_sigma)) {
        frozen_.utime = f.utime;
        frozen_.fix = dr->pose;
        frozen_.covariance = tighter_of(dr->covariance, fix_cov + d * d.transpose());
        frozen_.odometry = dr_last_;
        frozen_.path_m = dr_path_m_;
        frozen_.turn_rad = dr_turn_rad_;
        frozen_.open.setZero();
      }
    }
    last_off_dead_reckoning_ = uncertainty_.off_dead_reckoning;
    if (!tracker_.wants_dead_reckoning()) have_frozen_ = false;  // the stretch (if any) is over
    if (cfg_.uncertainty.dead_reckoning_gate_sigma > 0 && dr_odometry_ && dr_last_utime_ == f.utime &&
        uncertainty_.status == matcher::FitStatus::kOk && !tracker_.wants_dead_reckoning()) {
      // An anchor: the fix, its published covariance, its velocity and where the odometry was.
      Anchor a;
      a.utime = f.utime;
      a.fix = m->pose;
      a.covariance = uncertainty_.covariance;
      a.velocity = plan_velocity(*m);
      a.odometry = dr_last_;
      a.path_m = dr_path_m_;
      a.turn_rad = dr_turn_rad_;
      ok_frames_.push_back(a);
      while (ok_frames_.size() > 1 && double(f.utime - ok_frames_.front().utime) * 1e-6 > cfg_.uncertainty.dr_history_s)
        ok_frames_.pop_front();
    }
    in.covariance = uncertainty_.covariance;
    in.published_status = uncertainty_.status;
    in.status_text = uncertainty_.text;
  }
  add_map_error(f, &in.covariance);
  // A re-seed starts a new track: the window's old one (lost, and corrected by the fixes before) does not carry over.
  if (reseeded) window_.restart(finals);
  return window_.add(std::move(in), finals);
}

std::optional<DeadReckoned> Localizer::dead_reckoned(const FeatureFrame& f, const FramePose& sfr) {
  const UncertaintyConfig& u = cfg_.uncertainty;
  if (!(u.dead_reckoning_gate_sigma > 0)) return std::nullopt;
  const Eigen::Vector3d velocity = plan_velocity(sfr.match);
  // (Re)starts the odometry at this frame (its fix, the matcher's velocity): the anchors before cannot be related to it.
  // Inside a stretch that refused a fix against the dead reckoning the odometry then starts at a fix in doubt, and no
  // dead-reckoned pose is left to end the stretch against: it ends at the next OK fix unless a second fit near it
  // explains more points than it does (check_rival; corridor s1 mixed: a fix 2.3 m off, published OK, where a fit ~2 m
  // away explained 1.3x as many points), which makes the stretch's end a re-acquisition.
  auto restart = [&]() {
    if (dr_odometry_ && tracker_.refused_in_stretch()) reacquiring_without_dr_ = true;
    odometry::OdometryConfig oc;
    oc.max_points = u.dr_max_points;
    oc.static_support_m = u.dr_static_support_m;
    oc.prediction_sigma_m = u.dr_prediction_sigma_m;
    oc.prediction_sigma_rad = u.dr_prediction_sigma_rad;
    dr_odometry_.emplace(oc);
    dr_odometry_->set_pose(sfr.match.pose, velocity);
    dr_last_ = dr_odometry_->process(f).pose;
    dr_last_utime_ = f.utime;
    dr_velocity_ = velocity.head<2>();
    ok_frames_.clear();
    have_frozen_ = false;
    return std::optional<DeadReckoned>();
  };
  if (!dr_odometry_) return restart();
  // The gyro's yaw change since the odometry's last frame holds its yaw (dr_gyro_sigma_rad).
  if (u.dr_gyro_sigma_rad > 0 && cfg_.use_imu)
    if (const auto dyaw = imu_.integral(dr_last_utime_, f.utime)) dr_odometry_->set_yaw_change(*dyaw, u.dr_gyro_sigma_rad);
  const odometry::OdometryResult r = dr_odometry_->process(f);
  // A frame the odometry could not register breaks the chain, and so does a jump: the velocity changing from one frame
  // to the next by more than a platform does (the ICP caught another minimum: a moved wall, a local map of few frames).
  const double dt = (f.utime - dr_last_utime_) * 1e-6;
  if (!r.ok || !(dt > 0)) return restart();
  const Eigen::Vector2d v((r.pose.x - dr_last_.x) / dt, (r.pose.y - dr_last_.y) / dt);
  if ((v - dr_velocity_).norm() > u.dr_jump_mps) return restart();
  dr_velocity_ = v;
  dr_path_m_ += std::hypot(r.pose.x - dr_last_.x, r.pose.y - dr_last_.y);
  dr_turn_rad_ += std::abs(wrap_angle(r.pose.yaw - dr_last_.yaw));
  dr_last_ = r.pose;
  dr_last_utime_ = f.utime;
  // Where the odometry's own registration leaves a direction open (its 1-sigma there above poor_sigma_m: a corridor's
  // axis with nothing else in view) it carries its velocity, whose error (velocity_sigma_mps) times the frame's
  // interval adds to the 1-sigma along that direction, for every anchor.
  double open_dir = 0;
  if (weakest_horizontal((r.information + 1e-9 * Eigen::Matrix3d::Identity()).inverse(), &open_dir) > u.poor_sigma_m) {
    const double a = u.velocity_sigma_mps * dt;
    const Eigen::Matrix3d step = embed(a * a * Eigen::Vector2d(std::cos(open_dir), std::sin(open_dir)) *
                                       Eigen::Vector2d(std::cos(open_dir), std::sin(open_dir)).transpose());
    auto grow = [&](Anchor& an) {
      an.open = add_sigmas(an.open.isZero() ? Eigen::Matrix3d::Identity() * 1e-12 : embed(an.open), step).topLeftCorner<2, 2>();
    };
    for (Anchor& an : ok_frames_) grow(an);
    if (have_frozen_) grow(frozen_);
  }
  // The anchor: in a stretch the one frozen at its start (after a fix that failed this gate, the oldest it failed
  // against; else the one whose covariance grown by the odometry's error since is the smallest: the last OK frame is
  // often one the tracker carried along an open direction, a frame the plan fixed a second before is better known);
  // outside one the oldest.
  auto drift = [&](const Anchor& an) { return u.dr_sigma_m + u.dr_sigma_per_m * (dr_path_m_ - an.path_m); };
  const Anchor* a = nullptr;
  if (tracker_.wants_dead_reckoning()) {
    if (!have_frozen_ && !ok_frames_.empty()) {
      size_t k = 0;
      if (!last_off_dead_reckoning_) {
        double best = 0;
        for (size_t j = ok_frames_.size(); j-- > 0;) {
          const double v2 = std::pow(weakest_horizontal(ok_frames_[j].covariance, nullptr), 2) + std::pow(drift(ok_frames_[j]), 2);
          if (j + 1 == ok_frames_.size() || v2 < best) best = v2, k = j;
        }
      }
      frozen_ = ok_frames_[k];
      have_frozen_ = true;
      // The odometry goes on with the anchor's velocity (the plan fixed it; along a direction the odometry's points
      // leave open its own velocity is what it slid), unless the two differ by more than a platform's change
      // (dr_jump_mps): then the fixes before the stretch were sliding (a fix slid 0.5 m in 0.4 s, 1 m/s off), and the
      // odometry's points, taking it back to its own velocity, would count as a jump and start it again at the fix
      // in doubt.
      if ((frozen_.velocity.head<2>() - dr_velocity_).norm() <= u.dr_jump_mps) {
        dr_odometry_->set_velocity(frozen_.velocity);
        dr_velocity_ = frozen_.velocity.head<2>();
      }
    }
    if (have_frozen_) a = &frozen_;
  } else if (!ok_frames_.empty()) {
    a = &ok_frames_.front();
  }
  if (!a) return std::nullopt;
  const double sxy = drift(*a);
  const double syaw = u.dr_sigma_rad + u.dr_sigma_per_rad * (dr_turn_rad_ - a->turn_rad) + u.dr_sigma_rad_per_m * (dr_path_m_ - a->path_m);
  DeadReckoned d;
  d.pose = compose(a->fix, between(a->odometry, r.pose));
  d.covariance = a->covariance + Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal().toDenseMatrix();
  d.covariance.topLeftCorner<2, 2>() += a->open;
  return d;
}

std::optional<Localizer::Refit> Localizer::refit_from_dead_reckoning(const FeatureFrame& f, const FramePose& sfr, const Pose2& fix_at_ref,
                                                                     const Eigen::Matrix3d& fix_covariance, const DeadReckoned& dr,
                                                                     double t_ref, bool lost) {
  const UncertaintyConfig& u = cfg_.uncertainty;
  const double gate = chi2_3dof_of_sigmas(u.dead_reckoning_gate_sigma);
  auto off_dr = [&](const Pose2& p, const Eigen::Matrix3d& cov) { return mahalanobis2(pose_difference(p, dr.pose), dr.covariance + cov); };
  if (!lost && !(off_dr(sfr.match.pose, fix_covariance) > gate)) return std::nullopt;  // the fix agrees with the dead reckoning
  // The dead-reckoned pose at the de-skew reference (the fix's twist carries it there), registered from with the
  // matcher's tracking gate: the minimum nearest the odometry's track.
  const Pose2 ref_of_utime = matcher::exp_twist(sfr.match.twist, t_ref);
  matcher::MatcherConfig mc = cfg_.matcher;
  mc.max_correspondence_m = std::min(mc.max_correspondence_m, mc.gate_tracking_m);
  const matcher::MatchResult r = matcher::register_frame(lookup_, f, compose(dr.pose, ref_of_utime), mc);
  if (r.status != matcher::FitStatus::kOk) return std::nullopt;
  const int stride = matcher::budget_stride(f.points.size(), mc.stride, mc.max_points);
  const int own = matcher::evaluate_fit(lookup_, f, fix_at_ref, mc.inlier_m, stride).num_inliers;
  const int theirs = matcher::evaluate_fit(lookup_, f, r.solved, mc.inlier_m, stride).num_inliers;
  if (double(theirs) < u.dr_refit_ratio * double(std::max(1, own))) return std::nullopt;
  Refit out;
  out.at_ref = r.solved;
  out.match = sfr.match;  // the matcher's status, text and twist stay (a POOR fix's refit is published POOR still)
  out.match.pose = compose(r.solved, inverse(ref_of_utime));
  out.match.pose.yaw = wrap_angle(out.match.pose.yaw);
  out.match.solved = out.match.pose;
  out.match.sweep_pose = r.solved;
  out.match.fit = r.fit;
  out.match.covariance = r.covariance;
  if (!(off_dr(out.match.pose, r.covariance) <= gate)) return std::nullopt;  // converged beyond the gate too
  return out;
}

bool Localizer::check_rival(const FeatureFrame& f, const Pose2& fix, const DeadReckoned* dr, const Pose2& fix_at_utime) {
  const UncertaintyConfig& u = cfg_.uncertainty;
  matcher::MatcherConfig mc = cfg_.matcher;
  auto distinct = [&](const Pose2& p) {
    return std::hypot(p.x - fix.x, p.y - fix.y) > u.rival_distance_m || std::abs(wrap_angle(p.yaw - fix.yaw)) > u.rival_distance_rad;
  };
  const int stride = matcher::budget_stride(f.points.size(), mc.stride, mc.max_points);  // as register_frame's fit
  // Another explanation of the scan (rival.h): it explains structure the fix leaves off the plan, and what it leaves
  // off could stand in front of the plan's walls.
  auto explains_otherwise = [&](const Pose2& p, FitComparison* out) {
    // Within the searched region only: a fit that converged farther is another place along the plan (a corridor's
    // twin stretch), not a second reading of this one.
    if (!(u.rival_min_gained > 0) || std::hypot(p.x - fix.x, p.y - fix.y) > u.rival_search_m) return false;
    const FitComparison c = compare_fits(lookup_, f, fix, p, mc.inlier_m, stride);
    if (out) *out = c;
    return c.gained_structure >= u.rival_min_gained && c.lost_behind <= u.rival_max_behind_share * c.lost;
  };
  const int own = matcher::evaluate_fit(lookup_, f, fix, mc.inlier_m, stride).num_inliers;
  // After the dead reckoning was lost in a stretch (dead_reckoned()) the fix continues a track: a look-alike explaining 80 %
  // as many points (the corridor's twin stretch among people) is no evidence against it; one that explains more points
  // than the fix says the track holds a worse minimum.
  const double rival_ratio = reacquiring_without_dr_ ? std::max(1.0, u.rival_ratio) : u.rival_ratio;
  std::optional<Pose2> rival;
  int rival_inliers = 0;
  bool otherwise = false;
  FitComparison cmp;
  if (have_rival_) {
    // Carried with the track, registered again (the tracking gate).
    matcher::MatcherConfig mt = mc;
    mt.max_correspondence_m = std::min(mc.max_correspondence_m, mc.gate_tracking_m);
    const matcher::MatchResult m = matcher::register_frame(lookup_, f, compose(fix, rival_offset_), mt);
    if (m.status == matcher::FitStatus::kOk && distinct(m.solved)) {
      otherwise = explains_otherwise(m.solved, &cmp);
      // Kept while it is still an ambiguity; else searched again (another place may be one now).
      if (otherwise || m.fit.num_inliers >= rival_ratio * own || !(u.rival_min_gained > 0))
        rival = m.solved, rival_inliers = m.fit.num_inliers;
    }
  }
  if (!rival) {
    // None (yet, or it was lost): registrations from two rings of starts around the fix; the best distinct fit that
    // explains the scan otherwise, else the best distinct fit.
    std::vector<std::pair<int, Pose2>> fits;
    std::optional<Pose2> best;
    int best_inliers = 0;
    for (double r : {0.5 * u.rival_search_m, u.rival_search_m}) {
      mc.max_correspondence_m = std::max(mc.min_correspondence_m, 0.7 * r);
      for (int k = 0; k < 8; ++k) {
        const double a = fix.yaw + k * M_PI / 4;
        const matcher::MatchResult m =
            matcher::register_frame(lookup_, f, Pose2{fix.x + r * std::cos(a), fix.y + r * std::sin(a), fix.yaw}, mc);
        if (m.status != matcher::FitStatus::kOk || !distinct(m.solved)) continue;
        if (!best || m.fit.num_inliers > best_inliers) best = m.solved, best_inliers = m.fit.num_inliers;
        bool seen = false;  // several starts end in one fit
        for (const auto& q : fits)
          seen |= std::hypot(q.second.x - m.solved.x, q.second.y - m.solved.y) < 0.05 &&
                  std::abs(wrap_angle(q.second.yaw - m.solved.yaw)) < 0.01;
        if (!seen) fits.emplace_back(m.fit.num_inliers, m.solved);
      }
    }
    std::stable_sort(fits.begin(), fits.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    for (const auto& q : fits) {
      FitComparison c;
      if (explains_otherwise(q.second, &c)) {
        rival = q.second, rival_inliers = q.first, otherwise = true, cmp = c;
        break;
      }
    }
    if (!rival) rival = best, rival_inliers = best_inliers;
  }
  have_rival_ = rival.has_value();
  if (!rival) return false;
  rival_offset_ = between(fix, *rival);
  // Its points on drawn faces that other drawn walls hide from its sensor (a thick wall's outer face) are no inliers.
  // (cmp already compares this rival when it explains the scan otherwise.)
  const int hidden = otherwise ? cmp.gained_hidden : compare_fits(lookup_, f, fix, *rival, mc.inlier_m, stride).gained_hidden;
  const double share = double(rival_inliers - hidden) / double(std::max(1, own));
  if (share < rival_ratio && !otherwise) return false;
  if (dr && u.dead_reckoning_gate_sigma > 0 && !uncertainty_.off_dead_reckoning) {
    // The dead reckoning tells them apart: the fix within its gate (else the tracker said so), the rival beyond.
    const Pose2 r_at_utime = compose(fix_at_utime, between(fix, *rival));
    if (mahalanobis2(pose_difference(r_at_utime, dr->pose), dr->covariance + uncertainty_.covariance) >
        chi2_3dof_of_sigmas(u.dead_reckoning_gate_sigma))
      return false;
  }
  const Eigen::Vector3d d = pose_difference(*rival, fix);
  char b[200];
  if (share >= rival_ratio)
    std::snprintf(b, sizeof b, "re-acquired: a second fit %.2f m / %.1f deg away explains %.0f %% as many points", std::hypot(d[0], d[1]),
                  std::abs(d[2]) * 180 / M_PI, 100 * share);
  else
    std::snprintf(b, sizeof b, "re-acquired: a second fit %.2f m / %.1f deg away explains %d points the fix leaves off the plan "
                  "(%d of its own off it, in front of the walls)", std::hypot(d[0], d[1]), std::abs(d[2]) * 180 / M_PI, cmp.gained, cmp.lost);
  if (uncertainty_.status == matcher::FitStatus::kOk || uncertainty_.confirming) uncertainty_.text = b;
  if (uncertainty_.status == matcher::FitStatus::kOk) uncertainty_.status = matcher::FitStatus::kPoor;
  uncertainty_.covariance += d * d.transpose();
  uncertainty_.sigma_max_m = weakest_horizontal(uncertainty_.covariance, &uncertainty_.weak_direction_rad);
  tracker_.restart_confirmation();
  return true;
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
  feed_back(s.latest);
  return s;
}

void Localizer::feed_back(const std::optional<Pose>& latest) {
  // (The matcher only: the published uncertainty's track goes on, as in the two-process graph.)
  if (const auto r = take_reseed()) matcher_.set_pose(r->pose, r->search_m);
  else if (latest && cfg_.refine_from_window) refine(latest->utime, latest->pose);
}

}  // namespace fploc::localizer
