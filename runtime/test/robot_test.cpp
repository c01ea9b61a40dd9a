#include "fploc/runtime/robot.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include "fploc/runtime/bus.h"

using namespace fploc::rt;

TEST(Robot, ChannelNamespace) {
  EXPECT_EQ(robot_channel("", "FPLOC_POSE"), "FPLOC_POSE");
  EXPECT_EQ(robot_channel("r2", "FPLOC_POSE"), "r2/FPLOC_POSE");
  EXPECT_EQ(robot_channel("r2", ""), "");  // an unconnected port stays unconnected
  EXPECT_TRUE(valid_robot_name(""));
  EXPECT_TRUE(valid_robot_name("r2_left-A"));
  EXPECT_FALSE(valid_robot_name("r 2"));
  EXPECT_FALSE(valid_robot_name("r2/x"));
  EXPECT_FALSE(valid_robot_name(std::string(33, 'a')));
}

TEST(Robot, RobotOfGraphThenEnvironment) {
  fploc::Graph g;
  unsetenv("FPLOC_ROBOT");
  EXPECT_EQ(robot_of(&g), "");
  setenv("FPLOC_ROBOT", "env", 1);
  EXPECT_EQ(robot_of(&g), "env");
  g.set_robot("r1");
  EXPECT_EQ(robot_of(&g), "r1");
  unsetenv("FPLOC_ROBOT");
}

TEST(Robot, TtlMergedIntoLcmUrl) {
  fploc::Graph g;
  EXPECT_EQ(graph_lcm_url(g), kDefaultLcmUrl);
  g.set_lcm_ttl(1);
  EXPECT_EQ(graph_lcm_url(g), "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304");
  g.set_lcm_url("udpm://239.255.76.70:7670");
  EXPECT_EQ(graph_lcm_url(g), "udpm://239.255.76.70:7670?ttl=1");
  g.set_lcm_url("udpm://239.255.76.70:7670?recv_buf_size=100");
  EXPECT_EQ(graph_lcm_url(g), "udpm://239.255.76.70:7670?recv_buf_size=100&ttl=1");
  EXPECT_EQ(graph_lcm_url(g, "memq://"), "memq://");
}
