// Keep-latest inputs (Queue::kLatest, graph Port.queue): a live node that falls behind gets only the
// newest queued message and the skipped ones count as the port's drops; composed replay gets them all.
#include <fploc/imu_t.hpp>
#include <gtest/gtest.h>

#include "fploc/runtime/bus.h"
#include "fploc/runtime/node.h"
#include "fploc/runtime/validate.h"

using namespace fploc::rt;

namespace {
NodeSpec spec_with(const std::string& channel, Queue q) {
  return {"t", "", "test", {input<fploc::imu_t>("in", channel, q)}};
}
void publish_n(Bus& bus, const std::string& channel, int n) {
  for (int i = 0; i < n; ++i) {
    fploc::imu_t m{};
    m.seq = i;
    m.utime = 1000 * i;
    bus.lcm().publish(channel, &m);
  }
}
const PortCounters& counters(Context& ctx) { return ctx.stats().ports.front(); }
}  // namespace

TEST(Queue, LiveLatestTakesTheNewestAndCountsTheRestAsDrops) {
  Bus bus("memq://");
  Context ctx(bus, spec_with("Q_LATEST", Queue::kLatest), "n", nullptr, {}, "", false);
  std::vector<int64_t> got;
  ctx.subscribe<fploc::imu_t>("in", [&](const fploc::imu_t& m) { got.push_back(m.seq); });
  publish_n(bus, "Q_LATEST", 5);  // queued while the node was busy
  EXPECT_EQ(dispatch_live(bus), 5 + 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], 4);
  EXPECT_EQ(counters(ctx).dropped, 4);  // not 4 + the sequence gap again
  EXPECT_EQ(counters(ctx).messages, 1);
  fploc::imu_t m{};
  m.seq = 5;
  bus.lcm().publish("Q_LATEST", &m);
  dispatch_live(bus);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1], 5);
  EXPECT_EQ(counters(ctx).dropped, 4);  // a message that was not behind is no drop
}

TEST(Queue, GraphOverridesTheSpec) {
  Bus bus("memq://");
  Context ctx(bus, spec_with("Q_OVERRIDE", Queue::kLatest), "n", nullptr, {}, "", false);
  ctx.set_queue_overrides({{"in", Queue::kAll}});
  std::vector<int64_t> got;
  ctx.subscribe<fploc::imu_t>("in", [&](const fploc::imu_t& m) { got.push_back(m.seq); });
  publish_n(bus, "Q_OVERRIDE", 5);
  dispatch_live(bus);
  EXPECT_EQ(got, (std::vector<int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(counters(ctx).dropped, 0);
}

TEST(Queue, ComposedReplayDeliversEveryMessage) {
  Bus bus("memq://");
  Context ctx(bus, spec_with("Q_COMPOSED", Queue::kLatest), "n", nullptr, {}, "", true);
  std::vector<int64_t> got;
  ctx.subscribe<fploc::imu_t>("in", [&](const fploc::imu_t& m) { got.push_back(m.seq); });
  publish_n(bus, "Q_COMPOSED", 5);
  while (bus.lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(got, (std::vector<int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(counters(ctx).dropped, 0);
}

TEST(Queue, DescribeJsonCarriesThePolicy) {
  const auto s = parse_spec_json(spec_json(spec_with("X", Queue::kLatest)));
  ASSERT_EQ(s.ports.size(), 1u);
  EXPECT_EQ(s.ports[0].queue, Queue::kLatest);
  EXPECT_EQ(parse_spec_json(spec_json(spec_with("X", Queue::kAll))).ports[0].queue, Queue::kAll);
}
