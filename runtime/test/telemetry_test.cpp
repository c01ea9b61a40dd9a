#include <gtest/gtest.h>

#include "fploc/runtime/telemetry.h"

using namespace fploc::rt;

TEST(Latency, NearestRankPercentiles) {
  LatencyWindow w;
  EXPECT_EQ(w.percentile(0.5), 0.0);
  for (int i = 100; i >= 1; --i) w.add(i);
  EXPECT_EQ(w.percentile(0.5), 50.0);
  EXPECT_EQ(w.percentile(0.99), 99.0);
  EXPECT_EQ(w.percentile(1.0), 100.0);
  EXPECT_EQ(w.percentile(0.0), 1.0);
  EXPECT_DOUBLE_EQ(w.sum(), 5050.0);
}

TEST(Ports, SequenceGapsAreDrops) {
  PortCounters p;
  for (int64_t s : {0, 1, 2, 5, 6, 10}) p.observe_seq(s);
  EXPECT_EQ(p.dropped, 2 + 3);
  p.observe_seq(0);  // publisher restarted: not a drop
  p.observe_seq(1);
  EXPECT_EQ(p.dropped, 5);
}

TEST(NodeStats, PortsAreStableAndSummed) {
  NodeStats s;
  auto& a = s.port("scan", "OS1_SCAN", false);
  auto& b = s.port("out", "X", true);
  for (int i = 0; i < 50; ++i) s.port("p" + std::to_string(i), "C", false);
  a.messages = 3;
  b.messages = 4;
  a.dropped = 1;
  EXPECT_EQ(&a, &s.port("scan", "OS1_SCAN", false));
  EXPECT_EQ(s.messages(false), 3);
  EXPECT_EQ(s.messages(true), 4);
  EXPECT_EQ(s.dropped(), 1);
}

TEST(Cpu, BusyLoopShowsLoad) {
  CpuMeter m;
  volatile double x = 0;
  for (int i = 0; i < 20000000; ++i) x = x + i * 1e-9;
  const double pct = m.sample_percent();
  EXPECT_GT(pct, 10.0);
  EXPECT_LT(pct, 250.0);
}

// The window optimizer releases poses in bursts (a keyframe with the non-keyframes before it): at 10 Hz,
// 3 poses every 0.3 s. The rate must read 10 Hz whatever the phase, which a count over the last 1-2 s
// did not (7-13 Hz), nor may the first burst read as a spike.
TEST(RateMeter, BurstsReadTheirMeanRateAtEveryPhase) {
  for (double phase = 0; phase < 0.3; phase += 0.01) {
    RateMeter r;
    double t = 0;
    for (int burst = 0; burst < 40; ++burst, t += 0.3)
      for (int k = 0; k < 3; ++k) r.add(t + 1e-4 * k);
    const double now = t - 0.3 + phase;
    EXPECT_NEAR(r.rate_hz(now), 10.0, 0.45) << "phase " << phase;
  }
}

TEST(RateMeter, SteadyStreamStalledStreamAndTooFew) {
  RateMeter r(5.0);
  EXPECT_EQ(r.rate_hz(0.0), 0.0);
  for (int i = 0; i <= 100; ++i) r.add(0.1 * i);   // 10 Hz for 10 s
  EXPECT_NEAR(r.rate_hz(10.05), 10.0, 1e-6);
  EXPECT_NEAR(r.rate_hz(11.0), 10.0, 1e-6);          // idle 1 s: bursts a second apart are not a stall
  const double stalled_2s = r.rate_hz(12.0);          // idle 2 s: reads lower than 10
  EXPECT_LT(stalled_2s, 9.0);
  EXPECT_GT(stalled_2s, 5.0);
  EXPECT_EQ(r.rate_hz(15.1), 0.0);                   // every arrival left the window
  r.add(20.0);
  EXPECT_EQ(r.rate_hz(20.0), 0.0);                   // one arrival: no rate yet
  r.add(20.0005);
  r.add(20.001);
  EXPECT_LE(r.rate_hz(20.002), 2.0);                 // a first burst is not a 2000 Hz stream
}
