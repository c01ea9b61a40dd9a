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
