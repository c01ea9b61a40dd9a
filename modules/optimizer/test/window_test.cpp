#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fploc/matcher/map.h"
#include "fploc/matcher/matcher.h"
#include "fploc/optimizer/window.h"
#include "synthetic.h"

using namespace fploc;
using namespace fploc::optimizer;
using fploc::testing::room_with_pillars;
using fploc::testing::synth_frame;
using fploc::testing::SynthOptions;

namespace {

// A smooth path through the room at ~0.6 m/s, 10 Hz.
Pose2 truth_at(double t) { return {3.0 + 0.6 * t, 3.0 + 1.5 * std::sin(0.25 * t), 0.2 * std::sin(0.3 * t) + 0.1 * t}; }

struct SeqRun {
  std::vector<Pose2> truth;
  std::vector<matcher::MatchResult> sfr;
  std::vector<FeatureFrame> frames;
};

SeqRun make_run(const matcher::NearestLookup& lookup, const FloorPlan& plan, int n, const SynthOptions& base) {
  SeqRun run;
  matcher::Matcher m(lookup, matcher::MatcherConfig{});
  m.set_pose(truth_at(0));
  for (int k = 0; k < n; ++k) {
    const double t = 0.1 * k;
    SynthOptions so = base;
    so.seed = base.seed + uint32_t(k);
    run.truth.push_back(truth_at(t));
    if (so.sweep_s > 0) so.sweep_twist = matcher::log_twist(truth_at(t), truth_at(t + so.sweep_s), so.sweep_s);
    run.frames.push_back(synth_frame(plan, run.truth.back(), so, int64_t(std::llround(t * 1e6))));
    run.frames.back().scan_seq = k;
    run.sfr.push_back(m.process(run.frames.back()));
  }
  return run;
}

double rms_err(const std::vector<Pose2>& est, const std::vector<Pose2>& truth) {
  double s = 0;
  for (size_t i = 0; i < est.size(); ++i) s += std::pow(est[i].x - truth[i].x, 2) + std::pow(est[i].y - truth[i].y, 2);
  return std::sqrt(s / double(est.size()));
}

// A frame and its single-frame fix as the window's input (pose, twist, status).
FrameInput input_of(const FeatureFrame& f, const matcher::MatchResult& r) {
  FrameInput in;
  in.features = f;
  in.sfr = r.pose;
  in.twist = r.twist;
  in.status = r.status;
  return in;
}

std::vector<PoseOut> optimise(const matcher::NearestLookup& lookup, const SeqRun& run, OptimizerConfig cfg) {
  WindowOptimizer opt(lookup, cfg);
  std::vector<PoseOut> finals;
  for (size_t k = 0; k < run.frames.size(); ++k) {
    const PoseOut latest = opt.add(input_of(run.frames[k], run.sfr[k]), &finals);
    EXPECT_FALSE(latest.final_estimate);
    EXPECT_EQ(latest.utime, run.frames[k].utime);
  }
  opt.flush(&finals);
  return finals;
}

}  // namespace

TEST(WindowOptimizer, EveryFrameBecomesFinalOnceInOrderAndKeysAreOptimisedWTimes) {
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  SynthOptions so;
  so.noise_sigma = 0.02;
  const SeqRun run = make_run(*map.lookup, *map.plan, 60, so);
  OptimizerConfig cfg;
  cfg.max_final_delay_s = 0;           // keys final when they leave the window (10 keys span 2 s here)
  const auto finals = optimise(*map.lookup, run, cfg);
  ASSERT_EQ(finals.size(), run.frames.size());
  int keys = 0, keys_w = 0;
  for (size_t i = 0; i < finals.size(); ++i) {
    EXPECT_EQ(finals[i].utime, run.frames[i].utime);
    EXPECT_TRUE(finals[i].final_estimate);
    if (finals[i].keyframe) {
      ++keys;
      keys_w += finals[i].optimised == cfg.window;
      EXPECT_LE(finals[i].optimised, cfg.window);
    }
  }
  EXPECT_GT(keys, 20);                 // 0.6 m/s at 10 Hz, 0.1 m threshold: most frames are keys
  EXPECT_GE(keys_w, keys - cfg.window);  // all but the last W (flushed) were optimised W times
}

TEST(WindowOptimizer, ExactWithoutNoise) {
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  const SeqRun run = make_run(*map.lookup, *map.plan, 40, SynthOptions{});
  const auto finals = optimise(*map.lookup, run, OptimizerConfig{});
  std::vector<Pose2> est;
  for (const auto& f : finals) est.push_back(f.pose);
  EXPECT_LT(rms_err(est, run.truth), 1e-3);
}

TEST(WindowOptimizer, RegularisationSmoothsANoisySequence) {
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  SynthOptions so;
  so.beams = 60;            // few, noisy features: single-frame poses scatter by centimetres
  so.noise_sigma = 0.08;
  so.clutter_fraction = 0.1;
  so.seed = 11;
  const SeqRun run = make_run(*map.lookup, *map.plan, 100, so);
  std::vector<Pose2> sfr;
  for (const auto& r : run.sfr) sfr.push_back(r.pose);
  OptimizerConfig cfg;
  const auto finals = optimise(*map.lookup, run, cfg);
  ASSERT_EQ(finals.size(), run.frames.size());
  std::vector<Pose2> wo;
  for (const auto& f : finals) wo.push_back(f.pose);
  const double e_sfr = rms_err(sfr, run.truth), e_wo = rms_err(wo, run.truth);
  std::printf("rms position error: single-frame %.4f m, windowed %.4f m\n", e_sfr, e_wo);
  EXPECT_LT(e_wo, e_sfr);
  // Without the velocity terms the window is just W independent single-frame problems.
  cfg.alpha = cfg.beta = 0;
  const auto plain = optimise(*map.lookup, run, cfg);
  std::vector<Pose2> pl;
  for (const auto& f : plain) pl.push_back(f.pose);
  EXPECT_LT(e_wo, rms_err(pl, run.truth));
}

TEST(WindowOptimizer, StationarySensorMakesAKeyframePerIntervalSoItsPosesKeepComing) {
  // A robot standing still for 6 s: without a time rule its frames wait for a keyframe that never comes
  // (no final pose until it moves); with keyframe_interval_s every second is a keyframe, and with a window
  // of 3 the poses up to 2 s are final while it still stands at 5.9 s.
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  for (const double interval : {0.0, 1.0}) {
    OptimizerConfig cfg;
    cfg.window = 3;
    cfg.keyframe_interval_s = interval;
    cfg.max_final_delay_s = 0;         // finals only from keys leaving the window (the next test: with it)
    WindowOptimizer opt(*map.lookup, cfg);
    std::vector<PoseOut> finals;
    int keys = 0;
    for (int k = 0; k < 60; ++k) {
      FrameInput in;
      in.features = synth_frame(*map.plan, {8, 3, 0.5}, SynthOptions{}, k * 100000);
      in.sfr = {8, 3, 0.5};
      keys += opt.add(in, &finals).keyframe;
    }
    const size_t before_flush = finals.size();
    opt.flush(&finals);
    EXPECT_EQ(finals.size(), 60u);
    for (const auto& f : finals) EXPECT_NEAR(std::hypot(f.pose.x - 8, f.pose.y - 3), 0.0, 1e-3);
    if (interval == 0) {
      EXPECT_EQ(keys, 1);
      EXPECT_EQ(before_flush, 0u);
    } else {
      EXPECT_EQ(keys, 6);                  // t = 0, 1, ..., 5 s
      EXPECT_EQ(before_flush, 21u);        // keys at 0, 1, 2 s left the window of 3, and the frames up to the last
    }
  }
}

TEST(WindowOptimizer, FinalPosesLagTheNewestFrameByAtMostMaxFinalDelay) {
  // A robot that stands 6 s (before a lift), moves off at 0.2 m/s for 4 s and stands again: keys every 1 s
  // (keyframe_interval_s) and every 0.5 s (0.1 m), so W = 10 keys span 5-10 s. Without max_final_delay_s a
  // frame is final when its key leaves the window: FPLOC_POSE up to ~W keyframe intervals behind the sensor.
  // With it every frame is final max_final_delay_s after it (at the newest frame's time), once, in order,
  // and where the window would have put it later.
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  auto truth = [](int k) { return Pose2{8.0 + 0.2 * std::clamp(0.1 * k - 6.0, 0.0, 4.0), 3.0, 0.5}; };
  const int n = 150;
  std::vector<std::vector<PoseOut>> runs;
  for (const double max_delay : {0.0, 1.0}) {
    OptimizerConfig cfg;
    cfg.max_final_delay_s = max_delay;
    WindowOptimizer opt(*map.lookup, cfg);
    std::vector<PoseOut> finals;
    double worst_s = 0;
    for (int k = 0; k < n; ++k) {
      FrameInput in;
      in.features = synth_frame(*map.plan, truth(k), SynthOptions{}, k * 100000);
      in.features.scan_seq = k;
      in.sfr = truth(k);
      const size_t had = finals.size();
      opt.add(in, &finals);
      for (size_t i = had; i < finals.size(); ++i) worst_s = std::max(worst_s, (k * 100000 - finals[i].utime) * 1e-6);
    }
    const size_t before_flush = finals.size();
    opt.flush(&finals);
    ASSERT_EQ(finals.size(), size_t(n));
    for (int k = 0; k < n; ++k) {
      EXPECT_EQ(finals[k].utime, k * 100000);
      EXPECT_TRUE(finals[k].final_estimate);
    }
    std::printf("max_final_delay_s %.1f: final poses up to %.1f s behind the newest frame\n", max_delay, worst_s);
    if (max_delay == 0) {
      EXPECT_GT(worst_s, 5.0);
    } else {
      EXPECT_LE(worst_s, max_delay + 1e-9);  // frames every 0.1 s: out exactly when the frame 1 s newer comes
      EXPECT_EQ(before_flush, size_t(n - 10));
    }
    runs.push_back(std::move(finals));
  }
  // The same window (keys) either way; a pose out early is the window's estimate of it then, not after W
  // solves: here about 5 mm from it at most (the regularisation's pull where the robot moves off and stops).
  double worst_m = 0;
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(runs[0][k].keyframe, runs[1][k].keyframe) << k;
    worst_m = std::max(worst_m, std::hypot(runs[1][k].pose.x - runs[0][k].pose.x, runs[1][k].pose.y - runs[0][k].pose.y));
  }
  EXPECT_LT(worst_m, 0.01);
}

TEST(WindowOptimizer, PoorFramesAreNeverKeyframes) {
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  WindowOptimizer opt(*map.lookup, OptimizerConfig{});
  std::vector<PoseOut> finals;
  for (int k = 0; k < 10; ++k) {
    FrameInput in;
    in.features = synth_frame(*map.plan, {4.0 + 0.2 * k, 3, 0}, SynthOptions{}, k * 100000);
    in.sfr = {4.0 + 0.2 * k, 3, 0};
    in.status = k % 2 ? matcher::FitStatus::kPoor : matcher::FitStatus::kOk;
    const PoseOut o = opt.add(in, &finals);
    EXPECT_EQ(o.keyframe, k % 2 == 0);
    EXPECT_EQ(o.status, in.status);
  }
}

TEST(WindowOptimizer, MotionCompensatedPosesAreAtUtime) {
  // A rotating sensor (each beam measured 0..0.1 s after utime from the moving pose): the single-frame
  // and the windowed poses are both the poses at utime, not the mid-sweep pose v * 50 ms away.
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  SynthOptions so;
  so.noise_sigma = 0.01;
  so.sweep_s = 0.1;
  const SeqRun run = make_run(*map.lookup, *map.plan, 80, so);
  std::vector<Pose2> sfr;
  for (const auto& r : run.sfr) sfr.push_back(r.pose);
  const auto finals = optimise(*map.lookup, run, OptimizerConfig{});
  ASSERT_EQ(finals.size(), run.frames.size());
  std::vector<Pose2> wo;
  for (const auto& f : finals) wo.push_back(f.pose);
  const double e_sfr = rms_err(sfr, run.truth), e_wo = rms_err(wo, run.truth);
  std::printf("rms position error at utime: single-frame %.4f m, windowed %.4f m (0.6 m/s: mid-sweep is 0.03 m away)\n",
              e_sfr, e_wo);
  EXPECT_LT(e_sfr, 0.008);
  EXPECT_LT(e_wo, 0.008);
}

TEST(WindowOptimizer, UnknownGravityIsInterpolatedFromNeighbours) {
  // Frames whose segmenter had no z / roll / pitch (its "unknown" sigmas, z = 0): the final poses take
  // them from the nearest frames that had them (interpolated in time, held at the start).
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  WindowOptimizer opt(*map.lookup, OptimizerConfig{});
  std::vector<PoseOut> finals;
  for (int k = 0; k < 30; ++k) {
    FrameInput in;
    in.features = synth_frame(*map.plan, {4.0 + 0.05 * k, 3, 0}, SynthOptions{}, k * 100000);
    in.sfr = {4.0 + 0.05 * k, 3, 0};
    const bool unknown = k == 0 || k == 10 || k == 11;
    in.features.z = unknown ? 0.0 : 1.20 + 0.01 * k;
    in.features.z_sigma = unknown ? 1e3 : 0.01;
    in.features.roll = unknown ? 0.0 : 0.002 * k;
    in.features.roll_pitch_sigma = unknown ? M_PI : 0.001;
    opt.add(in, &finals);
  }
  opt.flush(&finals);
  ASSERT_EQ(finals.size(), 30u);
  EXPECT_NEAR(finals[0].z, 1.21, 1e-12);          // held from the first known
  EXPECT_NEAR(finals[10].z, 1.20 + 0.10, 1e-9);   // between frames 9 and 12
  EXPECT_NEAR(finals[11].z, 1.20 + 0.11, 1e-9);
  EXPECT_NEAR(finals[10].roll, 0.002 * 10, 1e-9);
  EXPECT_NEAR(finals[5].z, 1.25, 1e-12);          // known ones pass through
}

// The compact (square-root information) frame terms give the solver the same cost, gradient and
// Gauss-Newton matrix as one residual per point: the same poses, to rounding.
TEST(WindowOptimizer, CompactTermsGiveThePerPointSolution) {
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  SynthOptions so;
  so.beams = 90;
  so.noise_sigma = 0.03;
  so.clutter_fraction = 0.1;
  so.seed = 5;
  const SeqRun run = make_run(*map.lookup, *map.plan, 60, so);
  OptimizerConfig per_point;
  per_point.compact_terms = false;
  OptimizerConfig compact;
  compact.compact_terms = true;
  const auto a = optimise(*map.lookup, run, per_point);
  const auto b = optimise(*map.lookup, run, compact);
  ASSERT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i)
    worst = std::max({worst, std::abs(a[i].pose.x - b[i].pose.x), std::abs(a[i].pose.y - b[i].pose.y),
                      std::abs(a[i].pose.yaw - b[i].pose.yaw)});
  EXPECT_LT(worst, 1e-6);
  std::vector<Pose2> est;
  for (const auto& f : b) est.push_back(f.pose);
  EXPECT_LT(rms_err(est, run.truth), 0.02);
}

// A pose whose covariance (the fix's plus its offset from the fix) is wide is not published OK.
TEST(WindowOptimizer, PoseFarFromItsFixIsPublishedPoor) {
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  const SeqRun run = make_run(*map.lookup, *map.plan, 5, SynthOptions{});
  OptimizerConfig cfg;
  cfg.poor_sigma_m = 0.1;
  WindowOptimizer opt(*map.lookup, cfg);
  std::vector<PoseOut> finals;
  for (size_t k = 0; k < run.frames.size(); ++k) {
    FrameInput in = input_of(run.frames[k], run.sfr[k]);
    in.covariance = Eigen::Matrix3d::Identity() * 1e-6;
    if (k == 4) in.sfr.x += 0.4;  // a fix 0.4 m off its frame's points: the window stays where they fit
    const PoseOut o = opt.add(in, &finals);
    if (k < 4) {
      EXPECT_EQ(o.status, matcher::FitStatus::kOk) << k;
    } else {
      EXPECT_EQ(o.status, matcher::FitStatus::kPoor);
      EXPECT_NE(o.status_text.find("from the frame's fix"), std::string::npos) << o.status_text;
    }
  }
}

TEST(WindowOptimizer, ARideEndingOnAFloorMovesTheRidesFramesNotYetFinal) {
  // A robot stands in a lift car for a 6 s ride: its z is the IMU's double integral, off by 0.5 d t^2 (a
  // residual acceleration d = 0.002 m/s^2: 3.5 cm at the end), its sigma growing as 0.5 a t^2 (the floor
  // tracker's). The arrival's z (the new floor + the height in the car, 5 mm) ends the stretch: the frames
  // not final yet (the last max_final_delay_s = 1 s) move by the share of the 3.6 cm their sigma had grown;
  // the frames already out keep theirs. Control: without end_z_stretch the last second keeps its 3 cm.
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  const Pose2 at{8.0, 3.0, 0.5};
  const int start = 20, end = 80;  // ride frames [start, end); frame `end` is the arrival
  auto ride_t = [&](int k) { return std::max(0, k - start) * 0.1; };
  // The car moves for 5 s (smooth start and stop) and stands 1 s before the IMU calls it a rest (the arrival).
  auto truth_z = [&](int k) { return 4.4 - 3.2 * 0.5 * (1 - std::cos(M_PI * std::min(1.0, ride_t(k) / 5.0))); };
  auto err = [&](int k) { return k < end ? 0.5 * 0.002 * ride_t(k) * ride_t(k) : 0.0; };
  for (const bool end_stretch : {false, true}) {
    WindowOptimizer opt(*map.lookup, OptimizerConfig{});
    std::vector<PoseOut> finals;
    for (int k = 0; k <= end + 5; ++k) {
      FrameInput in;
      in.features = synth_frame(*map.plan, at, SynthOptions{}, k * 100000);
      in.features.scan_seq = k;
      in.features.z = truth_z(k) + err(k);
      const double r = k >= start && k < end ? 0.5 * 0.02 * ride_t(k) * ride_t(k) : 0.0;
      in.features.z_sigma = std::hypot(0.005, r);
      in.sfr = at;
      if (k == end && end_stretch) {
        opt.end_z_stretch(in.features);  // (the node, when the matcher says the floor changed)
        opt.flush(&finals);
      }
      opt.add(in, &finals);
    }
    opt.flush(&finals);
    ASSERT_EQ(finals.size(), size_t(end + 6));
    for (int k = 0; k <= end + 5; ++k) {
      const double e = finals[k].z - truth_z(k);
      if (k < end - 10 || k >= end) {
        EXPECT_NEAR(e, err(k), 1e-9) << k;  // final before the arrival (or after it): as it came
      } else if (end_stretch) {
        EXPECT_LT(std::abs(e), 0.25 * err(k)) << k;  // 2.6-3.5 cm -> under a quarter
      } else {
        EXPECT_GT(e, 0.024) << k;
      }
    }
  }
}

TEST(WindowOptimizer, ARestartedTrackIsNotInterpolatedFromTheOldOne) {
  // After restart() (the Localizer re-seeding a lost matcher) the next frame is a new track 1 m away, 0.1 s after the
  // last frame: its pose at utime is its own, not a blend with the old track's last output (a sweeping sensor's
  // frames are published at utime, interpolated between the outputs at their mid-sweep times).
  auto map = matcher::make_localization_map(room_with_pillars(), "brute-force");
  SynthOptions so;
  so.noise_sigma = 0.005;
  so.sweep_s = 0.1;
  const SeqRun run = make_run(*map.lookup, *map.plan, 21, so);
  WindowOptimizer opt(*map.lookup, OptimizerConfig{});
  std::vector<PoseOut> finals;
  for (size_t k = 0; k < 20; ++k) opt.add(input_of(run.frames[k], run.sfr[k]), &finals);
  opt.restart(&finals);
  const size_t before = finals.size();
  EXPECT_EQ(before, 20u);  // the old track made final, once
  matcher::MatchResult moved = run.sfr[20];
  moved.pose.x += 1.0;  // the frame as if the robot stood 1 m on (its features too)
  SynthOptions s20 = so;
  s20.seed = so.seed + 20;
  const Pose2 t20{run.truth[20].x + 1.0, run.truth[20].y, run.truth[20].yaw};
  s20.sweep_twist = run.sfr[20].twist;
  const FeatureFrame f20 = synth_frame(*map.plan, t20, s20, run.frames[20].utime);
  moved.status = matcher::FitStatus::kPoor;  // (a re-seed goes in as a POOR frame)
  const PoseOut latest = opt.add(input_of(f20, moved), &finals);
  opt.flush(&finals);
  ASSERT_EQ(finals.size(), before + 1);
  const double e_latest = std::hypot(latest.pose.x - moved.pose.x, latest.pose.y - moved.pose.y);
  const double e_final = std::hypot(finals.back().pose.x - moved.pose.x, finals.back().pose.y - moved.pose.y);
  std::printf("the first frame after a restart, 1 m from the old track: latest %.3f m, final %.3f m from its fix\n", e_latest,
              e_final);
  EXPECT_LT(e_latest, 0.02);
  EXPECT_LT(e_final, 0.02);
}
