#include "fploc/optimizer/window.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fploc/matcher/plan_terms.h"

namespace fploc::optimizer {
namespace {

// sqrt(alpha) (v^{m+1} - v^m), sqrt(beta) (w^{m+1} - w^m) for three consecutive key poses.
struct VelocityReg {
  double dt0, dt1, sa, sb;
  template <typename T>
  bool operator()(const T* p0, const T* p1, const T* p2, T* r) const {
    using std::atan2;
    using std::cos;
    using std::sin;
    const T d0 = p1[2] - p0[2], d1 = p2[2] - p1[2];
    const T w0 = atan2(sin(d0), cos(d0)) / dt0, w1 = atan2(sin(d1), cos(d1)) / dt1;
    r[0] = sa * ((p2[0] - p1[0]) / dt1 - (p1[0] - p0[0]) / dt0);
    r[1] = sa * ((p2[1] - p1[1]) / dt1 - (p1[1] - p0[1]) / dt0);
    r[2] = sb * (w1 - w0);
    return true;
  }
};

// The same with the velocities in the body frame: the constant body twists of the two segments
// (SE(2) logarithm / dt, series for the small keyframe turns), so a constant-speed turn - what a pushed
// platform does in a curve - costs nothing, where world-frame velocities change direction.
struct BodyVelocityReg {
  double dt0, dt1, sa, sb;
  template <typename T>
  static void twist(const T* p, const T* q, double dt, T* v) {
    using std::atan2;
    using std::cos;
    using std::sin;
    const T c = cos(p[2]), s = sin(p[2]);
    const T dx = q[0] - p[0], dy = q[1] - p[1];
    const T rx = c * dx + s * dy, ry = -s * dx + c * dy;
    const T d = q[2] - p[2];
    const T th = atan2(sin(d), cos(d));
    const T t2 = th * th;
    const T a = T(1) - t2 / T(6) * (T(1) - t2 / T(20)), b = th / T(2) * (T(1) - t2 / T(12));
    const T den = a * a + b * b;
    v[0] = (a * rx + b * ry) / den / T(dt);
    v[1] = (-b * rx + a * ry) / den / T(dt);
    v[2] = th / T(dt);
  }
  template <typename T>
  bool operator()(const T* p0, const T* p1, const T* p2, T* r) const {
    T v0[3], v1[3];
    twist(p0, p1, dt0, v0);
    twist(p1, p2, dt1, v1);
    r[0] = sa * (v1[0] - v0[0]);
    r[1] = sa * (v1[1] - v0[1]);
    r[2] = sb * (v1[2] - v0[2]);
    return true;
  }
};

Eigen::Vector3d diff(const Pose2& a, const Pose2& b) { return {a.x - b.x, a.y - b.y, wrap_angle(a.yaw - b.yaw)}; }
Pose2 plus(const Pose2& a, const Eigen::Vector3d& c) { return {a.x + c[0], a.y + c[1], wrap_angle(a.yaw + c[2])}; }

// A non-keyframe's correction (pose - single-frame pose) at tau: interpolated in time between a key's (ca at
// ta) and the next key's (cb at tb).
Eigen::Vector3d interpolate_correction(int64_t tau, int64_t ta, const Eigen::Vector3d& ca, int64_t tb,
                                       const Eigen::Vector3d& cb) {
  const double span = double(tb - ta);
  const double s = span > 0 ? std::clamp(double(tau - ta) / span, 0.0, 1.0) : 1.0;
  Eigen::Vector3d d = cb - ca;
  d[2] = wrap_angle(d[2]);
  return ca + s * d;
}

}  // namespace

WindowOptimizer::WindowOptimizer(const matcher::NearestLookup& lookup, OptimizerConfig cfg) : lookup_(lookup), cfg_(std::move(cfg)) {
  cfg_.window = std::max(1, cfg_.window);
  if (cfg_.linear_solver != "sparse" && cfg_.linear_solver != "dense")
    throw std::invalid_argument("optimizer linear_solver '" + cfg_.linear_solver + "': expected sparse or dense");
  if (cfg_.linear_solver == "sparse" && !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) &&
      !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE))
    cfg_.linear_solver = "dense";
}
WindowOptimizer::~WindowOptimizer() = default;

Eigen::Vector3d WindowOptimizer::newest_correction() const {
  if (!window_.empty()) {
    const Key& k = window_.back();
    return diff(Pose2{k.x[0], k.x[1], k.x[2]}, k.f.sfr_tau);
  }
  if (!finals_.empty()) return finals_.back().correction;
  return Eigen::Vector3d::Zero();
}

PoseOut WindowOptimizer::make_out(const Frame& f, const Pose2& pose_tau_in, bool key, Stamped* prev) const {
  const Pose2 pose_tau{pose_tau_in.x, pose_tau_in.y, wrap_angle(pose_tau_in.yaw)};
  PoseOut o;
  o.utime = f.in.features.utime;
  o.scan_seq = f.in.features.scan_seq;
  const double span = (f.tau - prev->tau) * 1e-6;
  if (prev->valid && prev->tau <= o.utime && o.utime <= f.tau && span > 0 && span <= 0.5) {
    // Geodesic interpolation between the two poses at utime.
    const matcher::Twist2 v = matcher::log_twist(prev->pose, pose_tau, span);
    o.pose = compose(prev->pose, matcher::exp_twist(v, (o.utime - prev->tau) * 1e-6));
  } else {
    o.pose = compose(pose_tau, matcher::exp_twist(f.in.twist, -f.t_ref));
  }
  *prev = {true, f.tau, pose_tau};
  fill_gravity(&o, f.in.features);
  o.keyframe = key;
  o.status = f.in.status;
  if (f.in.status == matcher::FitStatus::kOk || f.in.status == matcher::FitStatus::kPoor)
    o.status = std::max(f.in.status, f.in.published_status);  // the worse of the two (OK < POOR < LOST)
  o.status_text = f.in.status_text;
  o.covariance = f.in.covariance;
  if (cfg_.covariance_offset) {
    // The covariance is of the frame's own fix (its single-frame pose); the published pose lies d from it
    // (the window smooths, or holds what the fix does not see): the error's second moment is P + d d^T.
    const Eigen::Vector3d d = diff(o.pose, f.in.sfr);
    o.covariance += d * d.transpose();
    if (cfg_.poor_sigma_m > 0 && o.status == matcher::FitStatus::kOk) {
      const Eigen::Matrix2d C = 0.5 * (o.covariance.topLeftCorner<2, 2>() + o.covariance.topLeftCorner<2, 2>().transpose());
      const double tr = C.trace(), det = C.determinant();
      const double sigma = std::sqrt(std::max(0.0, tr / 2 + std::sqrt(std::max(0.0, tr * tr / 4 - det))));
      if (sigma > cfg_.poor_sigma_m) {
        char b[160];
        std::snprintf(b, sizeof b, "window pose %.2f m from the frame's fix (1 sigma %.2f m)", std::hypot(d[0], d[1]), sigma);
        o.status = matcher::FitStatus::kPoor;
        o.status_text = b;
      }
    }
  }
  o.z_sigma = f.in.features.z_sigma;
  o.roll_pitch_sigma = f.in.features.roll_pitch_sigma;
  return o;
}

void WindowOptimizer::fill_gravity(PoseOut* o, const FeatureFrame& f) const {
  // The segmenter's roll/pitch/z hold at utime + attitude_t (mid-sweep), the pose at utime: interpolate
  // them to utime between the nearest frames that have them. A frame without them (sigma "unknown") is
  // filled the same way; with a neighbour on one side only (the newest frame), its own values (or that
  // neighbour's) are used.
  o->roll = f.roll;
  o->pitch = f.pitch;
  o->z = f.z;
  const bool z_ok = z_known(f);
  const bool rp_ok = roll_pitch_known(f);
  auto fill = [&](bool Gravity::*known, bool self_known, auto get, double* out) {
    const Gravity* before = nullptr;
    const Gravity* after = nullptr;
    for (const auto& g : gravity_) {
      if (!(g.*known)) continue;
      if (g.t <= f.utime) before = &g;
      else if (!after) after = &g;
    }
    if (before && after) {
      const double s = double(f.utime - before->t) / double(after->t - before->t);
      *out = get(*before) + s * (get(*after) - get(*before));
    } else if (self_known) {
      // Its own entry when it holds at utime (end_z_stretch may have moved its z).
      if (before && before->t == f.utime + std::llround(f.attitude_t * 1e6)) *out = get(*before);
    } else if (before || after) {
      *out = get(before ? *before : *after);
    }
  };
  fill(&Gravity::z_known, z_ok, [](const Gravity& g) { return g.z; }, &o->z);
  fill(&Gravity::rp_known, rp_ok, [](const Gravity& g) { return g.roll; }, &o->roll);
  fill(&Gravity::rp_known, rp_ok, [](const Gravity& g) { return g.pitch; }, &o->pitch);
}

void WindowOptimizer::end_z_stretch(const FeatureFrame& f) {
  if (cfg_.z_stretch_ratio <= 0 || !z_known(f)) return;
  auto last = std::find_if(gravity_.rbegin(), gravity_.rend(), [](const Gravity& g) { return g.z_known; });
  if (last == gravity_.rend()) return;
  const double s_end = last->z_sigma, s = f.z_sigma;
  if (!(s_end > cfg_.z_stretch_ratio * s && s_end > cfg_.z_stretch_min_sigma_m)) return;
  const double e = f.z - last->z;
  for (auto it = last; it != gravity_.rend(); ++it) {
    if (!it->z_known) continue;
    if (it->z_sigma <= s) break;  // the stretch began after this frame
    it->z += e * (it->z_sigma - s) / (s_end - s);
    it->z_sigma = s;              // (said once: the next frame does not end it again)
  }
}

PoseOut WindowOptimizer::add(FrameInput in, std::vector<PoseOut>* finals) {
  {
    const FeatureFrame& f = in.features;
    gravity_.push_back({f.utime + std::llround(f.attitude_t * 1e6), f.roll, f.pitch, f.z,
                        roll_pitch_known(f), z_known(f), f.z_sigma});
    // Keep what the frames still to be output may need (and a little before).
    int64_t oldest = f.utime;
    if (!pending_.empty()) oldest = std::min(oldest, pending_.front().in.features.utime);
    if (!window_.empty()) oldest = std::min(oldest, window_.front().f.in.features.utime);
    while (gravity_.size() > 2 && gravity_[1].t < oldest - 5'000'000) gravity_.pop_front();
  }
  Frame fr;
  fr.in = std::move(in);
  const int64_t t = fr.in.features.utime;
  fr.t_ref = matcher::mean_time(fr.in.features);
  fr.tau = t + std::llround(fr.t_ref * 1e6);
  fr.sfr_tau = compose(fr.in.sfr, matcher::exp_twist(fr.in.twist, fr.t_ref));
  bool key = fr.in.status == matcher::FitStatus::kOk;
  if (key && have_last_key_) {
    const double d = std::hypot(fr.in.sfr.x - last_key_sfr_.x, fr.in.sfr.y - last_key_sfr_.y);
    const double a = std::abs(wrap_angle(fr.in.sfr.yaw - last_key_sfr_.yaw));
    const double since_key_s = (t - last_key_utime_) * 1e-6;
    key = d >= cfg_.keyframe_distance_m || a >= cfg_.keyframe_angle_rad ||
          (cfg_.keyframe_interval_s > 0 && since_key_s >= cfg_.keyframe_interval_s - 1e-6);
    if (key && since_key_s > cfg_.max_keyframe_gap_s) restart(finals);  // a long gap: the velocities across it mean nothing
  }
  PoseOut o;
  if (!key) {
    o = make_out(fr, plus(fr.sfr_tau, newest_correction()), false, &last_latest_);
    pending_.push_back(std::move(fr));
  } else {
    Key k;
    k.f = std::move(fr);
    deskew(k.f.in.features, k.f.in.twist, k.f.t_ref, &k.deskewed);
    const Pose2 init = plus(k.f.sfr_tau, newest_correction());
    k.x[0] = init.x;
    k.x[1] = init.y;
    k.x[2] = init.yaw;
    last_key_sfr_ = k.f.in.sfr;
    last_key_utime_ = t;
    have_last_key_ = true;
    window_.push_back(std::move(k));
    while (int(window_.size()) > cfg_.window) finalize_front(finals);
    solve();
    const Key& nk = window_.back();
    o = make_out(nk.f, Pose2{nk.x[0], nk.x[1], nk.x[2]}, true, &last_latest_);
    o.optimised = nk.optimised;
  }
  if (cfg_.max_final_delay_s > 0) finalize_until(t - std::llround(cfg_.max_final_delay_s * 1e6), finals);
  return o;
}

void WindowOptimizer::solve() {
  ceres::Problem::Options po;
  po.disable_all_safety_checks = true;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Solver::Options so;
  // Each keyframe's floor-plan block touches only its own 3 parameters: the normal equations of the
  // window are block-sparse (band of 3x3 blocks from the velocity terms). The dense solver forms
  // J^T J from a dense (2 N W) x 3W Jacobian, W times the work.
  // With compact terms the whole Jacobian is (4 W + 3 (W - 2)) x 3 W: dense is cheaper than any sparse
  // factorisation's set-up.
  so.linear_solver_type = cfg_.linear_solver == "dense" || cfg_.compact_terms ? ceres::DENSE_NORMAL_CHOLESKY
                                                                               : ceres::SPARSE_NORMAL_CHOLESKY;
  so.num_threads = 1;
  so.max_num_iterations = std::max(1, cfg_.max_iterations);
  so.logging_type = ceres::SILENT;
  matcher::AssignOptions ao;
  ao.gate_m = cfg_.gate_m;
  ao.group_rule = cfg_.group_rule;
  ao.element_weight = cfg_.element_weight;
  ao.stride = cfg_.stride;
  ao.element_quota = cfg_.element_quota;
  ao.askew_max_m = cfg_.askew_max_m;
  ao.askew_point_sigma_m = cfg_.as_built.point_sigma_m;
  // Anchors: the last final key poses, held fixed (optional).
  double anchors[2][3];
  std::vector<std::pair<double*, int64_t>> chain;  // pose block, utime
  if (cfg_.anchor_final) {
    for (size_t i = 0; i < finals_.size(); ++i) {
      anchors[i][0] = finals_[i].pose_tau.x;
      anchors[i][1] = finals_[i].pose_tau.y;
      anchors[i][2] = finals_[i].pose_tau.yaw;
      chain.push_back({anchors[i], finals_[i].tau});
    }
  }
  for (auto& k : window_) chain.push_back({k.x, k.f.tau});
  for (int outer = 0; outer < std::max(1, cfg_.rounds); ++outer) {
    // Look-ups: a key keeps its correspondences while its pose stays within relook_m / relook_rad of
    // where they were looked up (the residuals re-evaluate the closest point on the candidates at every
    // evaluation anyway); a round in which no key needed a new look-up would repeat the last solve.
    bool changed = outer == 0;
    for (auto& k : window_) {
      const Pose2 xk{k.x[0], k.x[1], k.x[2]};
      if (k.as_valid && std::hypot(xk.x - k.as_pose.x, xk.y - k.as_pose.y) <= cfg_.relook_m &&
          std::abs(wrap_angle(xk.yaw - k.as_pose.yaw)) <= cfg_.relook_rad)
        continue;
      matcher::AssignOptions aok = ao;
      const size_t np = k.deskewed.points.size();
      aok.stride = matcher::budget_stride(np, cfg_.stride, cfg_.max_points);
      if (matcher::selects_per_element(lookup_, aok)) {
        if (!k.sel_valid) {
          matcher::select_points(lookup_, k.deskewed, xk, aok, &k.sel);
          k.sel_valid = true;
        }
        aok.points = &k.sel;
      }
      std::vector<matcher::Assignment> as;
      assign(lookup_, k.deskewed, xk, aok, &as);
      changed |= !k.as_valid || as != k.as;
      k.as = std::move(as);
      k.as_pose = xk;
      k.as_valid = true;
      k.as_stride = aok.stride;
      k.term.reset();
    }
    if (!changed) break;
    // The keys' terms are theirs (kept across rounds and solves), the velocity terms this round's.
    std::vector<std::unique_ptr<ceres::CostFunction>> owned;
    ceres::Problem problem(po);
    for (auto& k : window_) {
      problem.AddParameterBlock(k.x, 3);
      // The paper's sigma_sfr sums over all of the frame's features: a point budget (every stride-th
      // point) estimates that sum with weight stride, so the balance against the velocity terms does not
      // depend on the budget. With element_quota the points kept for sure (their element has few) carry their
      // own sampling weight 1/sqrt(stride) (Assignment::sw), so they count once each.
      const double w = cfg_.budget_weight ? std::sqrt(double(k.as_stride)) : 1.0;
      if (!k.term) {
        const double xa[3] = {k.as_pose.x, k.as_pose.y, k.as_pose.yaw};
        k.term = matcher::make_frame_term(xa, lookup_, k.deskewed, k.as, cfg_.loss, cfg_.loss_scale_m, w,
                                          cfg_.compact_terms, &cfg_.as_built);
      }
      if (k.term) problem.AddResidualBlock(k.term.get(), nullptr, k.x);
    }
    for (size_t i = 0; i + 2 < chain.size(); ++i) {
      const double dt0 = (chain[i + 1].second - chain[i].second) * 1e-6;
      const double dt1 = (chain[i + 2].second - chain[i + 1].second) * 1e-6;
      if (!(dt0 > 1e-4 && dt1 > 1e-4)) continue;
      const double sa = std::sqrt(std::max(cfg_.alpha, 0.0)), sb = std::sqrt(std::max(cfg_.beta, 0.0));
      ceres::CostFunction* cost =
          cfg_.body_frame_velocity
              ? static_cast<ceres::CostFunction*>(new ceres::AutoDiffCostFunction<BodyVelocityReg, 3, 3, 3, 3>(
                    new BodyVelocityReg{dt0, dt1, sa, sb}))
              : new ceres::AutoDiffCostFunction<VelocityReg, 3, 3, 3, 3>(new VelocityReg{dt0, dt1, sa, sb});
      owned.emplace_back(cost);
      problem.AddResidualBlock(cost, nullptr, chain[i].first, chain[i + 1].first, chain[i + 2].first);
    }
    if (cfg_.anchor_final)
      for (size_t i = 0; i < finals_.size(); ++i)
        if (problem.HasParameterBlock(anchors[i])) problem.SetParameterBlockConstant(anchors[i]);
    ceres::Solver::Summary sum;
    ceres::Solve(so, &problem, &sum);
  }
  for (auto& k : window_) ++k.optimised;
  ++solves_;
}

void WindowOptimizer::emit_final(const Frame& f, const Pose2& pose_tau, bool key, int optimised,
                                 std::vector<PoseOut>* finals) {
  PoseOut o = make_out(f, pose_tau, key, &last_final_);
  o.final_estimate = true;
  o.optimised = optimised;
  if (finals) finals->push_back(std::move(o));
}

void WindowOptimizer::emit_pending_until(int64_t tau, const Eigen::Vector3d& corr_next, std::vector<PoseOut>* finals) {
  while (!pending_.empty() && pending_.front().tau < tau) {
    const Frame& f = pending_.front();
    const Eigen::Vector3d c =
        finals_.empty() ? corr_next
                        : interpolate_correction(f.tau, finals_.back().tau, finals_.back().correction, tau, corr_next);
    emit_final(f, plus(f.sfr_tau, c), false, 0, finals);
    pending_.pop_front();
  }
}

void WindowOptimizer::finalize_front(std::vector<PoseOut>* finals) {
  Key k = std::move(window_.front());
  window_.pop_front();
  const Pose2 p_tau = k.pose_tau();
  const Eigen::Vector3d corr = diff(p_tau, k.f.sfr_tau);
  emit_pending_until(k.f.tau, corr, finals);  // none left when k is out (they went out before it)
  if (!k.out) emit_final(k.f, p_tau, true, k.optimised, finals);
  finals_.push_back({k.f.tau, p_tau, corr});
  while (finals_.size() > 2) finals_.pop_front();
}

void WindowOptimizer::finalize_until(int64_t until, std::vector<PoseOut>* finals) {
  auto correction = [](const Key& k) { return diff(k.pose_tau(), k.f.sfr_tau); };
  size_t next = 0;  // the first key not out (those out lead the window: frames go out in time order)
  while (next < window_.size() && window_[next].out) ++next;
  for (;;) {
    Key* k = next < window_.size() ? &window_[next] : nullptr;
    if (!pending_.empty() && (!k || pending_.front().tau < k->f.tau)) {
      const Frame& f = pending_.front();
      if (f.in.features.utime > until) return;
      // Between the key before it (out, in the window or final) and the key after it, when there is one yet.
      const Key* a = next > 0 ? &window_[next - 1] : nullptr;
      const bool have_a = a || !finals_.empty();
      const int64_t ta = a ? a->f.tau : have_a ? finals_.back().tau : 0;
      const Eigen::Vector3d ca = a ? correction(*a) : have_a ? finals_.back().correction : Eigen::Vector3d::Zero();
      const Eigen::Vector3d c = !k ? ca : have_a ? interpolate_correction(f.tau, ta, ca, k->f.tau, correction(*k))
                                                 : correction(*k);
      emit_final(f, plus(f.sfr_tau, c), false, 0, finals);
      pending_.pop_front();
    } else if (k && k->f.in.features.utime <= until) {
      emit_final(k->f, k->pose_tau(), true, k->optimised, finals);
      k->out = true;
      ++next;
    } else {
      return;
    }
  }
}

void WindowOptimizer::flush(std::vector<PoseOut>* finals) {
  while (!window_.empty()) finalize_front(finals);
  const Eigen::Vector3d c = finals_.empty() ? Eigen::Vector3d::Zero() : finals_.back().correction;
  emit_pending_until(std::numeric_limits<int64_t>::max(), c, finals);
}

void WindowOptimizer::restart(std::vector<PoseOut>* finals) {
  flush(finals);
  finals_.clear();
  // (The next frame's output is not interpolated from the old track's last one, and it starts the keyframes.)
  last_final_.valid = last_latest_.valid = false;
  have_last_key_ = false;
}

}  // namespace fploc::optimizer
