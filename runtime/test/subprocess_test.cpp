#include "fploc/runtime/subprocess.h"

#include <gtest/gtest.h>

using fploc::rt::run_program;
using fploc::rt::RunOptions;

TEST(RunProgram, CapturesStdoutAndExitCode) {
  const auto r = run_program({"/bin/sh", "-c", "echo out; echo err >&2; exit 3"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.output, "out\n");  // stderr discarded by default
  EXPECT_EQ(r.problem, "exit code 3");
}

TEST(RunProgram, MergesStderrAndSearchesPath) {
  RunOptions o;
  o.merge_stderr = true;
  o.search_path = true;
  const auto r = run_program({"sh", "-c", "echo out; echo err >&2"}, o);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output, "out\nerr\n");
  EXPECT_EQ(r.problem, "");
}

TEST(RunProgram, KillsAtTheDeadlineWithItsChildren) {
  RunOptions o;
  o.timeout_s = 0.3;
  const auto r = run_program({"/bin/sh", "-c", "sleep 30 & sleep 30"}, o);
  EXPECT_TRUE(r.timed_out);
  EXPECT_EQ(r.exit_code, -1);
  EXPECT_EQ(r.problem, "timed out");
}

TEST(RunProgram, MissingProgramIsExit127) {
  const auto r = run_program({"/nonexistent/fploc-nothing"});
  EXPECT_EQ(r.exit_code, 127);
}
