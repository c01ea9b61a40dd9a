// Issue 14 item 7: segmenter + features against the OS-1 decode + XYZ of the SAME frames, in one run.
// The frames: 24 simulated OS-1-64 scans of room-small-loop-medium (real beam angles from ../shared when
// present, noise, clutter, ceiling patches), encoded into legacy OS-1 packets once; per iteration one frame
// is decoded from its packets and turned into XYZ (the driver's work), or segmented and its features
// extracted (the perception front end's work). Prints both and their ratio (CPU time per frame).
// The pipeline's segmenter also takes the IMU (graphs/paper.pbtxt: gyro de-skew, gravity fusion, the ground at a
// kink): BM_SegmenterPlusFeaturesImu runs it so, on 144 consecutive frames of the same sequence with each sweep's
// IMU samples fed before its scan, the segmenter reset when the sequence starts again, and its ratio is printed
// beside the one without the IMU (and BM_SegmenterPlusFeaturesImuNew's: a new segmenter at each restart).
// Each iteration's input arrives as in the pipeline: copied, outside the timing, into one receive buffer that is
// reused (a socket's receive leaves the packets, LCM's decode the scan, in the caches). Before the thirty-first
// round the lines read their inputs straight from the pools (24 frames' packets, 19 MB; 144 scans, 66 MB), so the
// decode streamed its packets from the shared L3 or memory and took 1.6x its time with received packets, more or
// less as the machine's other processes left the caches; the segmenter and features, bound by their own
// arithmetic, take the same time either way (docs/notes/perception.md, thirty-first round).
// Last, the ratio again with the two lines alternated in blocks (alternated_ratio), the figure least moved by the
// machine's load changing during the run, with received inputs and, for comparison, read from the pools.
//   build/bin/perception_ratio_bench [--benchmark_repetitions=N] [--alternate=BLOCKS (40; 0: none)] [--renew]
//                                    [--definitions=N (the IMU line reset vs renewed, alternated: N x 144 frames each)]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <utility>

#include "fploc/core/xyz.h"
#include "fploc/features/features.h"
#include "fploc/os1/metadata.h"
#include "fploc/os1/packet.h"
#include "fploc/segmentation/segmenter.h"
#include "fploc/sim/simulator.h"
#include "sim_sequence.h"

namespace {
using namespace fploc;

using FramePackets = std::vector<std::vector<uint8_t>>;  // one frame's packets

struct Frames {
  std::vector<Scan> scans;
  std::vector<bench::ImuFrame> consecutive;  // with their IMU samples (sim_sequence.h)
  os1::SensorInfo info;
  std::vector<FramePackets> packets;  // per frame
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

// A pool's items in turn, each copied into one reused buffer (its capacity kept) before it is worked on: the
// input as the pipeline receives it. With `received` false, the pool's own item (read from wherever it lies). The
// pool is its own copy (the decode writes its frame ids into the packets).
template <class T>
class Inputs {
 public:
  Inputs(std::vector<T> pool, bool received) : pool_(std::move(pool)), received_(received) {}
  T& next() {
    T& src = pool_[k_++ % pool_.size()];
    if (!received_) return src;
    rx_ = src;
    return rx_;
  }
  size_t count() const { return k_; }
  void restart() { k_ = 0; }

 private:
  std::vector<T> pool_;
  bool received_;
  T rx_;
  size_t k_ = 0;
};

// The driver's work on one frame: its packets assembled into a scan, then XYZ. A new frame id every call (written
// into the packets), so that every call assembles a whole frame.
class DecodeLine {
 public:
  explicit DecodeLine(const Frames& f) : fa_(f.info), lut_(make_xyz_lut(f.info.beams, f.info.columns_per_frame)) {}
  void frame(FramePackets& pk) {
    ++fid_;
    out_.clear();
    for (auto& p : pk) {
      for (int c = 0; c < 16; ++c) std::memcpy(p.data() + c * 788 + 10, &fid_, 2);
      fa_.add_packet(p.data(), p.size(), out_);
    }
    if (out_.empty()) return;
    scan_to_xyz(out_.back(), lut_, xyz_);
    benchmark::DoNotOptimize(xyz_.data());
    fa_.recycle(std::move(out_.back()));
  }

 private:
  os1::FrameAssembler fa_;
  XyzLut lut_;
  std::vector<Scan> out_;
  std::vector<Eigen::Vector3f> xyz_;
  uint16_t fid_ = 0;
};

// The pipeline's perception on one frame of the consecutive sequence: the sweep's IMU samples into the segmenter
// (as the segmenter node gives them, before the scan), the scan segmented, its features extracted. At the
// sequence's wrap (time going back to its start; outside any timing) the segmenter starts again: reset (the
// pipeline's case, since the forty-second round: a pipeline's segmenter lives for the whole run and would be
// reset on a time jump; Segmenter::reset gives a new segmenter's outputs bit for bit, its scratch arrays kept),
// or, with `renew`, replaced by a new one (the definition before: its first scans' allocations and page faults,
// once in a pipeline's run, every 144 frames here; docs/notes/perception.md, forty-second round).
class ImuLine {
 public:
  ImuLine(const Frames& f, bool received, bool renew = false) : f_(f), scans_(pool(f), received), renew_(renew) {
    sg_ = std::make_unique<seg::RingSegmenter>(seg::SegmenterConfig{});
  }
  bool at_wrap() const { return scans_.count() == f_.consecutive.size(); }
  void wrap() {
    if (renew_)
      sg_ = std::make_unique<seg::RingSegmenter>(seg::SegmenterConfig{});
    else
      sg_->reset();
    scans_.restart();
  }
  const Scan& receive() {
    imu_ = &f_.consecutive[scans_.count()];
    return *(scan_ = &scans_.next());
  }
  void frame() {
    bench::feed_imu(*sg_, *imu_);
    benchmark::DoNotOptimize(fx_.process(sg_->process(*scan_)).size());
  }

 private:
  static std::vector<Scan> pool(const Frames& f) {
    std::vector<Scan> out;
    for (const auto& fr : f.consecutive) out.push_back(fr.scan);
    return out;
  }
  const Frames& f_;
  Inputs<Scan> scans_;
  const bench::ImuFrame* imu_ = nullptr;
  const Scan* scan_ = nullptr;
  bool renew_;
  std::unique_ptr<seg::RingSegmenter> sg_;
  feat::FeatureExtractor fx_;
};

void BM_DecodeAndXyz(benchmark::State& st) {
  const auto& f = frames();
  DecodeLine line(f);
  Inputs<FramePackets> in(f.packets, true);
  for (auto _ : st) {
    st.PauseTiming();
    auto& pk = in.next();
    st.ResumeTiming();
    line.frame(pk);
  }
}
BENCHMARK(BM_DecodeAndXyz)->Unit(benchmark::kMicrosecond);

void BM_SegmenterPlusFeatures(benchmark::State& st) {
  const auto& f = frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  feat::FeatureExtractor fx;
  Inputs<Scan> in(f.scans, true);
  for (auto _ : st) {
    st.PauseTiming();
    const Scan& scan = in.next();
    st.ResumeTiming();
    benchmark::DoNotOptimize(fx.process(sg.process(scan)).size());
  }
}
BENCHMARK(BM_SegmenterPlusFeatures)->Unit(benchmark::kMicrosecond);

// As in the pipeline: the segmenter with the IMU, then the features (ImuLine; the segmenter reset at the
// sequence's restart). ...New: a new segmenter at each restart (the line's definition before the 42nd round).
void imu_line(benchmark::State& st, bool renew) {
  ImuLine line(frames(), true, renew);
  for (auto _ : st) {
    st.PauseTiming();
    if (line.at_wrap()) line.wrap();
    line.receive();
    st.ResumeTiming();
    line.frame();
  }
}
void BM_SegmenterPlusFeaturesImu(benchmark::State& st) { imu_line(st, false); }
BENCHMARK(BM_SegmenterPlusFeaturesImu)->Unit(benchmark::kMicrosecond);
void BM_SegmenterPlusFeaturesImuNew(benchmark::State& st) { imu_line(st, true); }
BENCHMARK(BM_SegmenterPlusFeaturesImuNew)->Unit(benchmark::kMicrosecond);

// The two stages alone (breakdown; not part of the ratio): the segmenter, and the features of segmentations
// computed once before the timing.
void BM_SegmenterOnly(benchmark::State& st) {
  const auto& f = frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  Inputs<Scan> in(f.scans, true);
  for (auto _ : st) {
    st.PauseTiming();
    const Scan& scan = in.next();
    st.ResumeTiming();
    benchmark::DoNotOptimize(sg.process(scan).wall.x.size());
  }
}
BENCHMARK(BM_SegmenterOnly)->Unit(benchmark::kMicrosecond);

void BM_FeaturesOnly(benchmark::State& st) {
  const auto& f = frames();
  seg::RingSegmenter sg(seg::SegmenterConfig{});
  std::vector<seg::Segmentation> segs;
  for (const auto& s : f.scans) segs.push_back(sg.process(s));
  feat::FeatureExtractor fx;
  Inputs<seg::Segmentation> in(segs, true);
  for (auto _ : st) {
    st.PauseTiming();
    const seg::Segmentation& sgm = in.next();
    st.ResumeTiming();
    benchmark::DoNotOptimize(fx.process(sgm).size());
  }
}
BENCHMARK(BM_FeaturesOnly)->Unit(benchmark::kMicrosecond);

// The ratio with the two lines alternated: blocks of 48 frames of each in turn, each frame timed in this thread's
// CPU time (its input's copy not timed), so that what changes in the machine over the run (other processes, what
// the shared caches hold) falls on both lines alike; the median and quartiles of the blocks' ratios.
double thread_cpu_us() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e6 + t.tv_nsec * 1e-3;
}

void alternated_ratio(int blocks, bool received, bool renew) {
  const auto& f = frames();
  DecodeLine decode(f);
  Inputs<FramePackets> packets(f.packets, received);
  ImuLine imu(f, received, renew);
  constexpr int kFrames = 48;
  for (int i = 0; i < 2 * kFrames; ++i) decode.frame(packets.next());  // warm both lines: a new segmenter's first
  for (int i = 0; i < kFrames; ++i) imu.receive(), imu.frame();         // scans are slower than the steady ones
  std::vector<double> d, s, r;
  for (int b = 0; b < blocks; ++b) {
    double busy = 0;
    for (int i = 0; i < kFrames; ++i) {
      auto& pk = packets.next();
      const double t0 = thread_cpu_us();
      decode.frame(pk);
      busy += thread_cpu_us() - t0;
    }
    d.push_back(busy / kFrames);
    busy = 0;
    for (int i = 0; i < kFrames; ++i) {
      if (imu.at_wrap()) imu.wrap();
      imu.receive();
      const double t0 = thread_cpu_us();
      imu.frame();
      busy += thread_cpu_us() - t0;
    }
    s.push_back(busy / kFrames);
    r.push_back(s.back() / d.back());
  }
  auto q = [](std::vector<double> v, double p) {
    std::sort(v.begin(), v.end());
    return v[size_t(p * double(v.size() - 1) + 0.5)];
  };
  std::printf(
      "alternated, %s%s, %d blocks of %d frames: decode + XYZ %.0f us, segmenter + features with the IMU %.0f us "
      "(medians); ratio per block: median %.2fx, quartiles %.2fx - %.2fx%s\n",
      received ? "inputs received (as in the pipeline)" : "inputs read from the pools (before the 31st round)",
      renew ? ", a new segmenter at each restart" : "", blocks, kFrames, q(d, 0.5), q(s, 0.5), q(r, 0.5), q(r, 0.25), q(r, 0.75), received ? " (target <= 2x)" : "");
}

// The IMU line's two definitions in one run (--definitions=BLOCKS): blocks of 48 frames of the line with its
// segmenter reset at the sequence's restart and of the line with a new segmenter there, in turn (each restart
// falls in every third block of each); their CPU time per frame over the whole run (the restarts included) and its
// ratio. The machine's load changing during the run falls on both alike.
void definitions_ratio(int triples) {
  const auto& f = frames();
  ImuLine reset(f, true, false), renew(f, true, true);
  constexpr int kFrames = 48;  // (three blocks: the sequence's 144 frames, one restart of each line)
  double tr = 0, tn = 0;
  std::vector<double> r;
  for (int k = 0; k < triples; ++k) {
    double br = 0, bn = 0;
    for (int b = 0; b < 3; ++b)
      for (ImuLine* line : {&reset, &renew}) {
        double& busy = line == &reset ? br : bn;
        for (int i = 0; i < kFrames; ++i) {
          if (line->at_wrap()) line->wrap();
          line->receive();
          const double t0 = thread_cpu_us();
          line->frame();
          busy += thread_cpu_us() - t0;
        }
      }
    tr += br;
    tn += bn;
    r.push_back(br / bn);
  }
  std::sort(r.begin(), r.end());
  const auto q = [&](double p) { return r[size_t(p * double(r.size() - 1) + 0.5)]; };
  std::printf(
      "the IMU line's two definitions alternated, %d x 3 blocks of %d frames: the segmenter reset at the restart %.1f "
      "us, a new segmenter there %.1f us per frame (means); reset / new %.4f, per 144 frames: median %.4f, quartiles "
      "%.4f - %.4f\n",
      triples, kFrames, tr / (3 * triples * kFrames), tn / (3 * triples * kFrames), tr / tn, q(0.5), q(0.25), q(0.75));
}

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
  int alternate_blocks = 40;  // --alternate=N: blocks of the alternated ratio (0: none)
  int definitions = 0;        // --definitions=N: the IMU line's two definitions alternated, N x 3 blocks (0: none)
  bool renew = false;         // --renew: the alternated ratio with a new segmenter at each restart (before the 42nd round)
  for (int i = 1; i < argc; ++i) {
    const bool alt = std::strncmp(argv[i], "--alternate=", 12) == 0, rn = std::strcmp(argv[i], "--renew") == 0,
               def = std::strncmp(argv[i], "--definitions=", 14) == 0;
    if (!alt && !rn && !def) continue;
    if (alt) alternate_blocks = std::atoi(argv[i] + 12);
    if (def) definitions = std::atoi(argv[i] + 14);
    if (rn) renew = true;
    for (int j = i; j + 1 < argc; ++j) argv[j] = argv[j + 1];
    --argc;
    --i;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  benchmark::Shutdown();
  const double d = rep.cpu_["BM_DecodeAndXyz"], s = rep.cpu_["BM_SegmenterPlusFeatures"],
               si = rep.cpu_["BM_SegmenterPlusFeaturesImu"], sn = rep.cpu_["BM_SegmenterPlusFeaturesImuNew"];
  if (d > 0 && s > 0)
    std::cout << "segmenter + features / (decode + XYZ) on the same frames: " << s << " us / " << d
              << " us = " << s / d << "x (target <= 2x)\n";
  if (d > 0 && si > 0)
    std::cout << "with the IMU, as in the pipeline (consecutive frames of the same sequence): " << si << " us / " << d
              << " us = " << si / d << "x (target <= 2x)\n";
  if (d > 0 && sn > 0)
    std::cout << "with the IMU, a new segmenter at each restart of the sequence (the definition before the 42nd round): "
              << sn << " us / " << d << " us = " << sn / d << "x\n";
  if (alternate_blocks > 0) {
    alternated_ratio(alternate_blocks, true, renew);
    alternated_ratio(alternate_blocks, false, renew);
  }
  if (definitions > 0) definitions_ratio(definitions);
  return 0;
}
