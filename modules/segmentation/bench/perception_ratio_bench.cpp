// Issue 14 item 7: segmenter + features against the OS-1 decode + XYZ of the SAME frames, in one run.
// The frames: 24 simulated OS-1-64 scans of room-small-loop-medium (real beam angles from ../shared when
// present, noise, clutter, ceiling patches), encoded into legacy OS-1 packets once; per iteration one frame
// is decoded from its packets and turned into XYZ (the driver's work), or segmented and its features
// extracted (the perception front end's work). Prints both and their ratio (CPU time per frame).
// The pipeline's segmenter also takes the IMU (graphs/paper.pbtxt: gyro de-skew, gravity fusion, the ground at a
// kink): BM_SegmenterPlusFeaturesImu runs it so, on 144 consecutive frames of the same sequence with each sweep's
// IMU samples fed before its scan, and its ratio is printed beside the one without the IMU.
//   build/bin/perception_ratio_bench [--benchmark_repetitions=N]
#include <benchmark/benchmark.h>

#include <cstring>
#include <iostream>
#include <map>
#include <memory>

#include "fploc/core/xyz.h"
#include "fploc/features/features.h"
#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"
#include "sim_sequence.h"

namespace {
using namespace fploc;

struct Frames {
  std::vector<Scan> scans;
  std::vector<bench::ImuFrame> consecutive;  // with their IMU samples (sim_sequence.h)
  os1::SensorInfo info;
  std::vector<std::vector<std::vector<uint8_t>>> packets;  // per frame
};

const Frames& frames() {
  static const Frames f = [] {
    Frames out;
    sim::Simulator sim(FloorPlan{}, bench::sequence_options());
    sim::SimScan s;
    for (int k = 0; k < sim.num_frames() && out.scans.size() < 24; k += 5) {
      sim.frame(k, s);
      out.scans.push_back(s.scan);
    }
    // Moving; 14.4 s, so that a new segmenter's one-off work (its look-up table, its first scan) weighs about
    // as little as in a run of the pipeline.
    out.consecutive = bench::imu_frames(100, 144);
    const Scan& s0 = out.scans.front();
    out.info = os1::make_sensor_info(s0.beams.altitude_deg, s0.beams.azimuth_deg);
    const auto fmt = os1::PacketFormat::from(out.info);
    for (size_t i = 0; i < out.scans.size(); ++i) {
      out.packets.emplace_back();
      os1::encode_frame(out.scans[i], uint16_t(i + 1), fmt, out.packets.back());
    }
    return out;
  }();
  return f;
}

void BM_DecodeAndXyz(benchmark::State& st) {
  const auto& f = frames();
  os1::FrameAssembler fa(f.info);
  const XyzLut lut = make_xyz_lut(f.info.beams, f.info.columns_per_frame);
  auto packets = f.packets;
  std::vector<Scan> out;
  std::vector<Eigen::Vector3f> xyz;
  uint16_t fid = 0;
  size_t k = 0;
  for (auto _ : st) {
    auto& pk = packets[k++ % packets.size()];
    ++fid;
    out.clear();
    for (auto& p : pk) {  // a new frame id every iteration: every iteration assembles a whole frame
      for (int c = 0; c < 16; ++c) std::memcpy(p.data() + c * 788 + 10, &fid, 2);
      fa.add_packet(p.data(), p.size(), out);
    }
    if (out.empty()) continue;
    scan_to_xyz(out.back(), lut, xyz);
    benchmark::DoNotOptimize(xyz.data());
    fa.recycle(std::move(out.back()));
  }
}
BENCHMARK(BM_DecodeAndXyz)->Unit(benchmark::kMicrosecond);

void BM_SegmenterPlusFeatures(benchmark::State& st) {
  const auto& f = frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  size_t k = 0;
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(sg.process(f.scans[k++ % f.scans.size()])).size());
}
BENCHMARK(BM_SegmenterPlusFeatures)->Unit(benchmark::kMicrosecond);

// As in the pipeline: the segmenter with the IMU (each sweep's samples fed before its scan, as the segmenter
// node does), then the features. The 144 frames are consecutive; at the wrap a new segmenter (outside the timing).
void BM_SegmenterPlusFeaturesImu(benchmark::State& st) {
  const auto& f = frames();
  auto sg = std::make_unique<seg::RingSegmenter>(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  size_t k = 0;
  for (auto _ : st) {
    if (k == f.consecutive.size()) {
      st.PauseTiming();
      sg = std::make_unique<seg::RingSegmenter>(seg::SegmenterConfig{});
      k = 0;
      st.ResumeTiming();
    }
    const auto& fr = f.consecutive[k++];
    bench::feed_imu(*sg, fr);
    benchmark::DoNotOptimize(fx.process(sg->process(fr.scan)).size());
  }
}
BENCHMARK(BM_SegmenterPlusFeaturesImu)->Unit(benchmark::kMicrosecond);

// The two stages alone (breakdown; not part of the ratio): the segmenter, and the features of segmentations
// computed once before the timing.
void BM_SegmenterOnly(benchmark::State& st) {
  const auto& f = frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  size_t k = 0;
  for (auto _ : st) benchmark::DoNotOptimize(sg.process(f.scans[k++ % f.scans.size()]).wall.x.size());
}
BENCHMARK(BM_SegmenterOnly)->Unit(benchmark::kMicrosecond);

void BM_FeaturesOnly(benchmark::State& st) {
  const auto& f = frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  std::vector<seg::Segmentation> segs;
  for (const auto& s : f.scans) segs.push_back(sg.process(s));
  feat::FeatureExtractor fx;
  size_t k = 0;
  for (auto _ : st) benchmark::DoNotOptimize(fx.process(segs[k++ % segs.size()]).size());
}
BENCHMARK(BM_FeaturesOnly)->Unit(benchmark::kMicrosecond);

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs)
      if (r.run_type == Run::RT_Iteration || r.aggregate_name == "median")
        cpu_[r.run_name.function_name] = r.GetAdjustedCPUTime();
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> cpu_;
};
}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  benchmark::Shutdown();
  const double d = rep.cpu_["BM_DecodeAndXyz"], s = rep.cpu_["BM_SegmenterPlusFeatures"],
               si = rep.cpu_["BM_SegmenterPlusFeaturesImu"];
  if (d > 0 && s > 0)
    std::cout << "segmenter + features / (decode + XYZ) on the same frames: " << s << " us / " << d
              << " us = " << s / d << "x (target <= 2x)\n";
  if (d > 0 && si > 0)
    std::cout << "with the IMU, as in the pipeline (consecutive frames of the same sequence): " << si << " us / " << d
              << " us = " << si / d << "x (target <= 2x)\n";
  return 0;
}
