#include <gtest/gtest.h>

#include "fploc/runtime/restart.h"

using namespace fploc::rt;

TEST(Restart, OnFailureBacksOffExponentiallyAndGivesUp) {
  fploc::RestartPolicy p;
  p.set_max_restarts(3);
  p.set_window_s(10);
  RestartTracker r(p);
  EXPECT_FALSE(r.on_exit(0.0, 1.0, false).restart);  // clean exit: not restarted under ON_FAILURE
  auto d = r.on_exit(0.0, 0.1, true);
  EXPECT_TRUE(d.restart);
  EXPECT_DOUBLE_EQ(d.delay, 0.1);
  EXPECT_DOUBLE_EQ(r.on_exit(0.5, 0.1, true).delay, 0.2);
  d = r.on_exit(1.0, 0.1, true);
  EXPECT_DOUBLE_EQ(d.delay, 0.4);
  EXPECT_EQ(d.in_window, 3);
  d = r.on_exit(1.5, 0.1, true);
  EXPECT_FALSE(d.restart);
  EXPECT_TRUE(d.give_up);
  // After the window has passed the node may restart again.
  EXPECT_TRUE(r.on_exit(12.0, 0.1, true).restart);
}

TEST(Restart, BackoffIsCappedAndResetsAfterALongRun) {
  fploc::RestartPolicy p;
  p.set_max_restarts(100);
  p.set_window_s(5);
  p.set_backoff_initial_s(1);
  p.set_backoff_factor(3);
  p.set_backoff_max_s(5);
  RestartTracker r(p);
  double t = 0;
  std::vector<double> delays;
  for (int i = 0; i < 4; ++i) delays.push_back(r.on_exit(t += 0.01, 0.01, true).delay);
  EXPECT_EQ(delays, (std::vector<double>{1, 3, 5, 5}));
  EXPECT_DOUBLE_EQ(r.on_exit(t += 100, 60, true).delay, 1.0);  // ran longer than the window
}

TEST(Restart, ModesAlwaysAndNever) {
  fploc::RestartPolicy p;
  p.set_mode(fploc::RestartPolicy::ALWAYS);
  EXPECT_TRUE(RestartTracker(p).on_exit(0, 1, false).restart);
  p.set_mode(fploc::RestartPolicy::NEVER);
  RestartTracker n(p);
  const auto d = n.on_exit(0, 1, true);
  EXPECT_FALSE(d.restart);
  EXPECT_FALSE(d.give_up);
}
