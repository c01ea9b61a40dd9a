#include "pipeline.h"

#include <time.h>

#include <cmath>

#include "fploc/eval/eval.h"
#include "fploc/features/features.h"
#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/odometry/odometry.h"
#include "fploc/optimizer/window.h"
#include "fploc/segmentation/segmenter.h"
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
  so.shared_dir = o.shared_dir;
  sim::Simulator sim(plan_in, so);
  const FloorPlan& plan = sim.world().plan();
  LocalizationMap map = make_localization_map(plan, o.lookup);
  seg::SegmenterConfig scfg;
  seg::RingSegmenter segmenter(scfg);
  feat::FeatureExtractor fx;
  const int n = o.max_frames > 0 ? std::min(o.max_frames, sim.num_frames()) : sim.num_frames();

  Result r;
  const StampedPose g0 = sim.ground_truth(sim.frame_time(0) + o.gt_offset_s);
  const Pose2 init{g0.p.x() + o.init_dx, g0.p.y() + o.init_dy, g0.rpy()[2] + o.init_dyaw};
  MatcherConfig mcfg;
  mcfg.max_points = o.matcher_points;
  Matcher matcher(*map.lookup, mcfg);
  matcher.set_pose(init);
  OptimizerConfig ocfg;
  ocfg.window = o.window;
  ocfg.alpha = o.alpha;
  ocfg.beta = o.beta;
  ocfg.keyframe_distance_m = o.keyframe_distance_m;
  ocfg.max_points = o.optimizer_points;
  WindowOptimizer opt(*map.lookup, ocfg);
  Odometry2D odo;
  odo.set_pose(init);
  std::vector<PoseOut> finals;
  const auto& imu = sim.imu();
  size_t imu_i = 0;
  double prev_t = -1;
  sim::SimScan f;
  double feat_total = 0;
  uint64_t drop_state = o.seed * 2654435761u + 1;
  for (int k = 0; k < n; ++k) {
    if (o.drop_fraction > 0) {
      drop_state = drop_state * 6364136223846793005ull + 1442695040888963407ull;
      if (double(drop_state >> 11) / double(1ull << 53) < o.drop_fraction) continue;
    }
    sim.frame(k, f);
    auto t0 = clk::now();
    const auto& s = segmenter.process(f.scan);
    r.us_segment += us_since(t0);
    t0 = clk::now();
    const auto& ft = fx.process(s);
    r.us_features += us_since(t0);
    FeatureFrame frame;
    frame.utime = ft.utime != 0 ? ft.utime : f.scan.utime;
    frame.scan_seq = k;
    frame.roll = ft.roll;
    frame.pitch = ft.pitch;
    frame.z = ft.z;
    for (size_t i = 0; i < ft.size(); ++i) {
      Feature2 p;
      p.p = {ft.x[i], ft.y[i]};
      p.kind = ft.kind[i] == 0 ? FeatureKind::kCorner : FeatureKind::kSurface;
      p.group = ft.group[i];
      p.t = ft.t.size() == ft.size() ? ft.t[i] : 0.f;
      frame.points.push_back(p);
    }
    feat_total += double(frame.points.size());
    // IMU yaw change since the previous processed scan (motion time = absolute - t0).
    const double t_rel = frame.utime * 1e-6 - so.t0_s;
    std::optional<double> dyaw;
    if (o.imu && prev_t >= 0) {
      double sum = 0;
      while (imu_i < imu.size() && imu[imu_i].t <= t_rel) {
        if (imu[imu_i].t > prev_t) sum += imu[imu_i].gyro.z() / sim.options().imu_rate_hz;
        ++imu_i;
      }
      dyaw = sum;
    }
    prev_t = t_rel;
    t0 = clk::now();
    const MatchResult m = matcher.process(frame, dyaw);
    r.us_matcher += us_since(t0);
    r.ok_frames += m.status == FitStatus::kOk;
    r.lost_frames += m.status == FitStatus::kLost;
    t0 = clk::now();
    FrameInput in;
    in.features = frame;
    in.sfr = m.pose;
    in.status = m.status;
    in.covariance = m.covariance;
    opt.add(std::move(in), &finals);
    r.us_optimizer += us_since(t0);
    t0 = clk::now();
    const OdometryResult od = odo.process(frame);
    r.us_odometry += us_since(t0);
    r.sfr.push_back(to_stamped(frame.utime, m.pose, frame.roll, frame.pitch, frame.z));
    r.odo.push_back(to_stamped(frame.utime, od.pose, frame.roll, frame.pitch, frame.z));
    const StampedPose g = sim.ground_truth(frame.utime * 1e-6 + o.gt_offset_s);
    r.gt.push_back(StampedPose::from(frame.utime * 1e-6, g.iso()));
    ++r.frames;
  }
  opt.flush(&finals);
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
