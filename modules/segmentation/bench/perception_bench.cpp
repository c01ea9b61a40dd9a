// Per-scan cost of the perception front end on a 64 x 1024 (65,536-point) OS-1-like scan of a furnished
// room: the paper's segmenter, the feature extractor, both together, and the PCL RANSAC segmenter.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <cstring>
#include <iostream>
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

#include "fploc/features/features.h"
#include "fploc/segmentation/ransac_segmenter.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/segmentation/synthetic.h"
#include "fploc/sim/simulator.h"
#include "sim_sequence.h"

namespace {
using namespace fploc;

const seg::synth::SynthScan& scan() {
  static const auto s = [] {
    seg::synth::SensorPose pose{-1.0, 0.5, 1.45, 1.0 * M_PI / 180, -0.8 * M_PI / 180, 0.4};
    return seg::synth::render(seg::synth::furnished_room(), pose, seg::synth::os1_like_beams(64), 1024, 0.02, 0.01, 3);
  }();
  return s;
}

void BM_RingSegmenter(benchmark::State& st) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  sg.process(scan().scan);  // warm: LUT, previous plane (steady state of a sequence)
  for (auto _ : st) benchmark::DoNotOptimize(sg.process(scan().scan).wall.size());
  st.counters["wall_points"] = double(sg.last().wall.size());
}
BENCHMARK(BM_RingSegmenter)->Unit(benchmark::kMicrosecond);

void BM_Features(benchmark::State& st) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  const seg::Segmentation s = sg.process(scan().scan);
  feat::FeatureExtractor fx;
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(s).size());
  st.counters["features"] = double(fx.process(s).size());
}
BENCHMARK(BM_Features)->Unit(benchmark::kMicrosecond);

void BM_SegmenterPlusFeatures(benchmark::State& st) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  sg.process(scan().scan);
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(sg.process(scan().scan)).size());
}
BENCHMARK(BM_SegmenterPlusFeatures)->Unit(benchmark::kMicrosecond);

// Simulated OS-1-64 scans of a sequence (room-small-loop-medium, every 5th frame: real beam angles and
// pixel shifts from ../shared, noise, dropouts, clutter, ceiling patches) with their gyro samples.
struct SimFrame {
  Scan scan;
  std::vector<std::pair<int64_t, Eigen::Vector3d>> gyro;
};
const std::vector<SimFrame>& sim_frames() {
  static const auto frames = [] {
    const sim::SimulatorOptions o = bench::sequence_options();
    sim::Simulator sim(FloorPlan{}, o);
    std::vector<SimFrame> out;
    sim::SimScan f;
    for (int k = 0; k < sim.num_frames() && out.size() < 24; k += 5) {
      sim.frame(k, f);
      SimFrame fr;
      fr.scan = f.scan;
      const double t0 = sim.frame_time(k) - o.t0_s, t1 = t0 + 1.0 / o.rate_hz;
      for (const auto& smp : sim.imu())
        if (smp.t >= t0 && smp.t < t1) fr.gyro.emplace_back(int64_t(std::llround((o.t0_s + smp.t) * 1e6)), smp.gyro);
      out.push_back(std::move(fr));
    }
    return out;
  }();
  return frames;
}

// Consecutive frames with every IMU sample (gyro and accelerometer): the IMU's whole path (gyro de-skew, gravity
// fusion, the ground at a kink), as in the pipeline.
const std::vector<bench::ImuFrame>& imu_frames() {
  static const auto frames = bench::imu_frames(100, 48);
  return frames;
}

// Segmenter + features on the simulated sequence, one scan per iteration (cycling through 24 scans);
// with_gyro: the IMU gyro samples of each sweep are fed first (rotation de-skew).
void sim_sequence(benchmark::State& st, bool with_gyro) {
  const auto& fr = sim_frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  size_t k = 0;
  for (auto _ : st) {
    const auto& f = fr[k++ % fr.size()];
    if (with_gyro)
      for (const auto& [t, w] : f.gyro) sg.add_gyro(w, t);
    benchmark::DoNotOptimize(fx.process(sg.process(f.scan)).size());
  }
}
void BM_SimSegmenterPlusFeatures(benchmark::State& st) { sim_sequence(st, false); }
BENCHMARK(BM_SimSegmenterPlusFeatures)->Unit(benchmark::kMicrosecond);
void BM_SimSegmenterPlusFeaturesGyro(benchmark::State& st) { sim_sequence(st, true); }
BENCHMARK(BM_SimSegmenterPlusFeaturesGyro)->Unit(benchmark::kMicrosecond);

void BM_RansacSegmenter(benchmark::State& st) {
  seg::RansacSegmenter sg(seg::SegmenterConfig{});
  sg.process(scan().scan);
  for (auto _ : st) benchmark::DoNotOptimize(sg.process(scan().scan).wall.size());
}
BENCHMARK(BM_RansacSegmenter)->Unit(benchmark::kMicrosecond);

// --profile=N: N scans of segmenter + features after a warm-up, instrumented for callgrind only there:
//   valgrind --tool=callgrind --instr-atstart=no build/bin/perception_bench --profile=20
// (--profile-sim=N: the simulated sequence instead of the synthetic scan; --profile-segmenter=N: no features)
// (instruction counts do not depend on the machine's load; divide by N for a per-scan figure).
int profile(int n, bool with_features, bool sim) {
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  auto next_scan = [&](int i) -> const Scan& { return sim ? sim_frames()[size_t(i) % sim_frames().size()].scan : scan().scan; };
  sg.process(next_scan(0));
  size_t sink = 0;
  CALLGRIND_START_INSTRUMENTATION;
  for (int i = 0; i < n; ++i) {
    const auto& s = sg.process(next_scan(i + 1));
    sink += with_features ? fx.process(s).size() : s.wall.size();
  }
  CALLGRIND_STOP_INSTRUMENTATION;
  // FNV-1a over the last outputs (planes, wall points, features): "optimised without changing results".
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* p, size_t bytes) {
    for (size_t i = 0; i < bytes; ++i) h = (h ^ static_cast<const uint8_t*>(p)[i]) * 1099511628211ull;
  };
  const auto& s = sg.last();
  mix(s.ceiling.coeffs.data(), sizeof(double) * 4);
  mix(s.ground.coeffs.data(), sizeof(double) * 4);
  for (const auto* v : {&s.wall.x, &s.wall.y, &s.wall.z, &s.wall.range, &s.wall.t}) mix(v->data(), v->size() * sizeof(float));
  if (with_features) {
    const auto& f = fx.process(s);
    // The same bytes as the extractor's float arrays (the frame's points hold exactly those floats).
    for (const auto& p : f.points) { const float x = float(p.p.x()); mix(&x, sizeof x); }
    for (const auto& p : f.points) { const float y = float(p.p.y()); mix(&y, sizeof y); }
    for (const auto& p : f.points) mix(&p.kind, 1);
    for (const auto& p : f.points) mix(&p.group, sizeof(int32_t));
  }
  std::cout << "profiled " << n << (sim ? " simulated" : " synthetic") << " scans ("
            << (with_features ? "segmenter + features" : "segmenter") << "), "
            << sink / size_t(std::max(1, n)) << " outputs per scan, result hash " << std::hex << h << std::dec << "\n";
  return 0;
}

// --hash-all=N: every output of the segmenter over N scans of the simulated sequence, without and with the gyro
// (de-skew), plus the synthetic scan, plus up to 48 consecutive scans with gyro and accelerometer (the IMU's whole
// path, as the pipeline runs it; with the ground's height and the status text): planes, status, roll/pitch/z and
// every wall array of EVERY scan (the --profile hashes cover only the last scan's planes and wall x/y/z/range/t).
// "Optimised without changing results". The room's flat floor leaves the ground-at-a-kink code without effect on
// these outputs: check a change there on the building journeys (`fploc bench building`, their poses).
int hash_all(int n) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* p, size_t bytes) {
    for (size_t i = 0; i < bytes; ++i) h = (h ^ static_cast<const uint8_t*>(p)[i]) * 1099511628211ull;
  };
  auto mix_seg = [&](const seg::Segmentation& s) {
    mix(s.ceiling.coeffs.data(), sizeof(double) * 4);
    mix(s.ground.coeffs.data(), sizeof(double) * 4);
    for (const double v : {s.roll, s.pitch, s.z, s.roll_pitch_sigma, s.z_sigma, s.ceiling.rms_m, s.ground.rms_m,
                           s.ceiling.tilt_sigma, s.ceiling.d_sigma})
      mix(&v, sizeof v);
    for (const int v : {int(s.status), s.ceiling.inliers, s.ceiling.beyond, s.ground.inliers, s.ground.beyond,
                        int(s.ceiling.found), int(s.ground.found), int(s.deskewed)})
      mix(&v, sizeof v);
    for (const auto* v : {&s.wall.x, &s.wall.y, &s.wall.z, &s.wall.range, &s.wall.t}) mix(v->data(), v->size() * sizeof(float));
    for (const auto* v : {&s.wall.ring, &s.wall.column}) mix(v->data(), v->size() * sizeof(int16_t));
  };
  size_t deskewed = 0, walls = 0;
  for (const bool gyro : {false, true}) {
    seg::RingSegmenter sg(seg::SegmenterConfig{});
    for (int i = 0; i < n; ++i) {
      const auto& f = sim_frames()[size_t(i) % sim_frames().size()];
      if (gyro)
        for (const auto& [t, w] : f.gyro) sg.add_gyro(w, t);
      const auto& s = sg.process(f.scan);
      mix_seg(s);
      deskewed += s.deskewed;
      walls += s.wall.size();
    }
  }
  {
    seg::RingSegmenter sg(seg::SegmenterConfig{});
    for (int i = 0; i < 3; ++i) mix_seg(sg.process(scan().scan));
  }
  // With the whole IMU (gyro and accelerometer) on consecutive frames, as in the pipeline.
  size_t with_imu = 0, kink = 0;
  {
    seg::RingSegmenter sg(seg::SegmenterConfig{});
    for (const auto& f : imu_frames()) {
      if (int(with_imu) == n) break;
      bench::feed_imu(sg, f);
      const auto& s = sg.process(f.scan);
      mix_seg(s);
      mix(&s.ground.under_m, sizeof(double));
      mix(s.status_text.data(), s.status_text.size());
      kink += s.status_text.find("ground:") != std::string::npos;
      ++with_imu;
    }
  }
  std::cout << "hashed 2 x " << n << " simulated scans (" << deskewed << " de-skewed, " << walls / size_t(2 * std::max(1, n))
            << " wall points per scan) + 3 synthetic + " << with_imu << " consecutive scans with the IMU (" << kink
            << " with a ground note): hash " << std::hex << h << std::dec << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--profile=", 10) == 0) return profile(std::atoi(argv[i] + 10), true, false);
    if (std::strncmp(argv[i], "--profile-sim=", 14) == 0) return profile(std::atoi(argv[i] + 14), true, true);
    if (std::strncmp(argv[i], "--hash-all=", 11) == 0) return hash_all(std::atoi(argv[i] + 11));
    if (std::strncmp(argv[i], "--profile-segmenter=", 20) == 0) return profile(std::atoi(argv[i] + 20), false, false);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
