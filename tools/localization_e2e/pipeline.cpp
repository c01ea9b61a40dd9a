#include "pipeline.h"

#include <time.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "fploc/eval/eval.h"
#include "fploc/features/features.h"
#include "fploc/localizer/localizer.h"
#include "fploc/matcher/map.h"
#include "fploc/odometry/odometry.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/config/perception.h"
#include "fploc/sim/simulator.h"

namespace fploc::e2e {
namespace {

// Thread CPU time: the machine is shared, wall-clock per stage would measure the neighbours.
struct clk {
  using time_point = double;
  static double now() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e6 + ts.tv_nsec * 1e-3;
  }
};
double us_since(double t) { return clk::now() - t; }

StampedPose to_stamped(int64_t utime, const Pose2& p, double roll, double pitch, double z) {
  return StampedPose::from_rpy(utime * 1e-6, Eigen::Vector3d(p.x, p.y, z), roll, pitch, p.yaw);
}

void score(const Trajectory& gt, const Trajectory& est, double* ate_rmse, double* rpe_mean) {
  if (est.empty()) return;
  const auto pairs = eval::associate(gt, est, 0.02);
  *ate_rmse = eval::ate(gt, est, pairs).trans.rmse;
  *rpe_mean = eval::rpe(gt, est, pairs, 1.0).trans.mean;
}

}  // namespace

Result run(const FloorPlan& plan_in, const Options& o) {
  sim::SimulatorOptions so;
  so.scenario = o.scenario;
  so.seed = o.seed;
  so.clutter = o.clutter;
  if (o.range_noise_m >= 0) so.range_noise_m = o.range_noise_m;
  so.wall_clutter = o.wall_clutter;
  so.shared_dir = o.shared_dir;
  sim::Simulator sim(plan_in, so);
  const FloorPlan& plan = sim.world().plan();
  matcher::LocalizationMap map = matcher::make_localization_map(plan, o.lookup);
  // The graph's nodes' configurations (their options' defaults).
  seg::RingSegmenter segmenter(config::config_of(SegmenterOptions{}));
  feat::FeatureExtractor fx(config::config_of(FeatureOptions{}));
  const int n = o.max_frames > 0 ? std::min(o.max_frames, sim.num_frames()) : sim.num_frames();

  Result r;
  const StampedPose g0 = sim.ground_truth(sim.frame_time(0) + o.gt_offset_s);
  const Pose2 init{g0.p.x() + o.init_dx, g0.p.y() + o.init_dy, g0.rpy()[2] + o.init_dyaw};
  localizer::Config cfg;
  cfg.matcher.max_points = o.matcher_points;
  cfg.optimizer.window = o.window;
  cfg.optimizer.alpha = o.alpha;
  cfg.optimizer.beta = o.beta;
  cfg.optimizer.keyframe_distance_m = o.keyframe_distance_m;
  cfg.optimizer.max_points = o.optimizer_points;
  cfg.optimizer.body_frame_velocity = o.body_frame_velocity;
  if (o.relook_m >= 0) {
    cfg.optimizer.relook_m = o.relook_m;
    cfg.optimizer.relook_rad = o.relook_m / 0.01 * cfg.optimizer.relook_rad;
  }
  cfg.use_imu = o.imu;
  cfg.initial_search_m = o.init_search_m;
  localizer::Localizer loc(*map.lookup, cfg);
  loc.set_pose(init);
  odometry::Odometry2D odo;
  odo.set_pose(init);
  std::vector<localizer::Pose> finals;
  const auto& imu = sim.imu();
  size_t imu_i = 0;
  sim::SimScan f;
  double feat_total = 0;
  uint64_t drop_state = o.seed * 2654435761u + 1;
  std::unique_ptr<FILE, int (*)(FILE*)> csv(o.frames_csv.empty() ? nullptr : std::fopen(o.frames_csv.c_str(), "w"), &std::fclose);
  if (!o.frames_csv.empty() && !csv) throw std::runtime_error(o.frames_csv + ": cannot write");
  if (csv) std::fprintf(csv.get(), "k,utime,status,points,inliers,inlier_ratio,rms_m,iterations,err_x_m,err_y_m,err_yaw_deg,vx,vy,w,z_sigma_m,err_z_m\n");
  for (int k = 0; k < n; ++k) {
    if (o.drop_fraction > 0) {
      drop_state = drop_state * 6364136223846793005ull + 1442695040888963407ull;
      if (double(drop_state >> 11) / double(1ull << 53) < o.drop_fraction) continue;
    }
    sim.frame(k, f);
    auto t0 = clk::now();
    const auto& s0 = segmenter.process(f.scan);
    r.us_segment += us_since(t0);
    seg::Segmentation s_gt;
    if (o.gt_gravity) {
      s_gt = s0;
      const Eigen::Vector3d rpy = sim.ground_truth(f.scan.utime * 1e-6 + 0.05).rpy();
      s_gt.roll = rpy[0];
      s_gt.pitch = rpy[1];
    }
    const seg::Segmentation& s = o.gt_gravity ? s_gt : s0;
    t0 = clk::now();
    const auto& ft = fx.process(s);
    r.us_features += us_since(t0);
    FeatureFrame frame = ft;  // the extractor's frame, as every stage consumes it (no wire type in between)
    frame.scan_seq = k;
    if (frame.utime == 0) frame.utime = f.scan.utime;
    feat_total += double(frame.points.size());
    // IMU samples up to the end of the sweep (when the scan is published), as in the simulator's log.
    const double t_pub = frame.utime * 1e-6 + 1.0 / sim.options().rate_hz - so.t0_s;
    for (; imu_i < imu.size() && imu[imu_i].t <= t_pub; ++imu_i)
      loc.add_imu(std::llround((so.t0_s + imu[imu_i].t) * 1e6), imu[imu_i].gyro.z());
    t0 = clk::now();
    const localizer::FramePose sfr = loc.register_frame(frame);
    r.us_matcher += us_since(t0);
    const matcher::MatchResult& m = sfr.match;
    r.ok_frames += m.status == matcher::FitStatus::kOk;
    if (csv) {
      const StampedPose g = sim.ground_truth(frame.utime * 1e-6 + o.gt_offset_s);
      std::fprintf(csv.get(), "%d,%lld,%s,%d,%d,%.4f,%.5f,%d,%.5f,%.5f,%.4f,%.4f,%.4f,%.4f,%.5f,%.5f\n", k, (long long)frame.utime,
                   to_string(m.status), m.fit.num_points, m.fit.num_inliers, m.fit.inlier_ratio, m.fit.rms_m, m.iterations,
                   m.pose.x - g.p.x(), m.pose.y - g.p.y(), wrap_angle(m.pose.yaw - g.rpy()[2]) * 180 / M_PI, m.twist.vx,
                   m.twist.vy, m.twist.w, frame.z_sigma, frame.z - g.p.z());
    }
    r.lost_frames += m.status == matcher::FitStatus::kLost;
    t0 = clk::now();
    // The window step, and its estimate of this frame predicts the next one (the graphs' `refined` input; or the
    // matcher is re-seeded, their `reseed`).
    loc.feed_back(loc.optimize(frame, sfr, &finals));
    r.us_optimizer += us_since(t0);
    t0 = clk::now();
    const odometry::OdometryResult od = odo.process(frame);
    r.us_odometry += us_since(t0);
    r.sfr.push_back(to_stamped(frame.utime, m.pose, sfr.roll, sfr.pitch, sfr.z));
    r.odo.push_back(to_stamped(frame.utime, od.pose, frame.roll, frame.pitch, frame.z));
    const StampedPose g = sim.ground_truth(frame.utime * 1e-6 + o.gt_offset_s);
    r.gt.push_back(StampedPose::from(frame.utime * 1e-6, g.iso()));
    ++r.frames;
  }
  loc.flush(&finals);
  for (const auto& p : finals) r.wo.push_back(to_stamped(p.utime, p.pose, p.roll, p.pitch, p.z));
  const int nf = std::max(1, r.frames);
  r.us_segment /= nf;
  r.us_features /= nf;
  r.us_matcher /= nf;
  r.us_optimizer /= nf;
  r.us_odometry /= nf;
  r.features_per_scan = feat_total / nf;
  for (size_t i = 1; i < r.gt.size(); ++i) {
    const double d = (r.gt[i].p - r.gt[i - 1].p).head<2>().norm(), dt = r.gt[i].t - r.gt[i - 1].t;
    r.length_m += d;
    if (dt > 0) r.max_speed = std::max(r.max_speed, d / dt);
  }
  if (r.gt.size() > 1) r.avg_speed = r.length_m / (r.gt.back().t - r.gt.front().t);
  score(r.gt, r.sfr, &r.ate_sfr, &r.rpe_sfr);
  score(r.gt, r.wo, &r.ate_wo, &r.rpe_wo);
  score(r.gt, r.odo, &r.ate_odo, &r.rpe_odo);
  auto flat = [](Trajectory t) {
    for (auto& p : t) p.p.z() = 0;
    return t;
  };
  const Trajectory gt_xy = flat(r.gt);
  score(gt_xy, flat(r.sfr), &r.ate_sfr_xy, &r.rpe_sfr_xy);
  score(gt_xy, flat(r.wo), &r.ate_wo_xy, &r.rpe_wo_xy);
  score(gt_xy, flat(r.odo), &r.ate_odo_xy, &r.rpe_odo_xy);
  return r;
}

}  // namespace fploc::e2e
